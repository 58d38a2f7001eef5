//! `weft run --gltf`: the kept frames as one animated binary glTF file, `run.glb`.
//!
//! Gathers what [`weft::export::gltf`] writes from the recorded frames: each cloth as a
//! triangle mesh with the world's vertex normals, each strand group as line strips through its
//! simulated points with its scalp as an ellipsoid, and each obstacle as the mesh the pictures
//! draw (analytic shapes tessellated, a plane as a finite quad around the cloth).

use std::ops::Range;
use std::path::Path;

use weft::export::{write_glb, GltfMesh, Topology};
use weft::render::shapes;

use crate::pictures::{Frame, CLOTH_COLORS, HAIR_COLORS, OBSTACLE_COLOR, SCALP_COLOR};

/// A scalp ellipsoid: positions, triangles, normals.
type Scalp = (Vec<[f32; 3]>, Vec<[u32; 3]>, Vec<[f32; 3]>);

/// An sRGB colour as glTF's linear RGBA.
fn linear(c: [u8; 3]) -> [f32; 4] {
    let l = |v: u8| {
        let s = v as f32 / 255.0;
        if s <= 0.04045 {
            s / 12.92
        } else {
            ((s + 0.055) / 1.055).powf(2.4)
        }
    };
    [l(c[0]), l(c[1]), l(c[2]), 1.0]
}

/// Area-weighted unit vertex normals of a triangle mesh (the rule `World::read_normals` uses).
fn vertex_normals(p: &[[f32; 3]], tris: &[[u32; 3]]) -> Vec<[f32; 3]> {
    let mut n = vec![[0.0f32; 3]; p.len()];
    for t in tris.iter().filter(|t| t.iter().all(|&i| (i as usize) < p.len())) {
        let [a, b, c] = t.map(|i| p[i as usize]);
        let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let m = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        for &i in t {
            for k in 0..3 {
                n[i as usize][k] += m[k];
            }
        }
    }
    n
}

/// Writes `path` from the kept `frames` of `world`'s run.
pub fn write_run(world: &weft::World, frames: &[Frame], path: &Path) -> weft::Result<()> {
    let Some(first) = frames.first() else {
        return Err(weft::WeftError::Scene("no frames were kept, so there is no glTF to write".into()));
    };
    let times: Vec<f32> = frames.iter().map(|f| (f.time - first.time) as f32).collect();
    let names: Vec<String> = (0..world.cloths().len()).map(|k| format!("cloth_{k}")).collect();
    let cloth_tris: Vec<Vec<[u32; 3]>> = world
        .cloths()
        .iter()
        .map(|c| {
            world.triangles()[c.first_triangle as usize..(c.first_triangle + c.triangle_count) as usize]
                .iter()
                .map(|t| t.map(|i| i - c.first))
                .collect()
        })
        .collect();
    let mut meshes = Vec::new();
    for (k, c) in world.cloths().iter().enumerate() {
        let r = c.first as usize..(c.first + c.rows * c.cols) as usize;
        meshes.push(GltfMesh {
            name: &names[k],
            color: linear(CLOTH_COLORS[k % CLOTH_COLORS.len()]),
            topology: Topology::Triangles(&cloth_tris[k]),
            positions: frames.iter().map(|f| &f.positions[r.clone()]).collect(),
            normals: frames
                .iter()
                .filter(|f| !f.normals.is_empty())
                .map(|f| &f.normals[r.clone()])
                .collect(),
        });
    }
    let groups = world.strands();
    let strand_names: Vec<String> = (0..groups.len()).map(|k| format!("strands_{k}")).collect();
    let scalp_names: Vec<String> = (0..groups.len()).map(|k| format!("scalp_{k}")).collect();
    let strips: Vec<Vec<Range<u32>>> = groups
        .iter()
        .map(|g| (0..g.count).map(|s| s * g.points..(s + 1) * g.points).collect())
        .collect();
    let scalps: Vec<Scalp> = groups
        .iter()
        .map(|g| {
            let (pos, tris) = shapes::uv_sphere([0.0; 3], 1.0, 48);
            let pos: Vec<[f32; 3]> = pos
                .iter()
                .map(|p| [0, 1, 2].map(|a| g.scalp.center[a] + p[a] * g.scalp.radii[a]))
                .collect();
            let n = vertex_normals(&pos, &tris);
            (pos, tris, n)
        })
        .collect();
    for (k, g) in groups.iter().enumerate() {
        let r = g.first as usize..(g.first + g.count * g.points) as usize;
        meshes.push(GltfMesh {
            name: &strand_names[k],
            color: linear(HAIR_COLORS[k % HAIR_COLORS.len()]),
            topology: Topology::LineStrips(&strips[k]),
            positions: frames.iter().map(|f| &f.positions[r.clone()]).collect(),
            normals: Vec::new(),
        });
        let (pos, tris, n) = &scalps[k];
        meshes.push(GltfMesh {
            name: &scalp_names[k],
            color: linear(SCALP_COLOR),
            topology: Topology::Triangles(tris),
            positions: vec![pos],
            normals: vec![n],
        });
    }
    let n_obstacles = first.obstacles.len();
    if frames.iter().any(|f| f.obstacles.len() != n_obstacles) {
        return Err(weft::WeftError::Scene("the number of obstacles changed during the run".into()));
    }
    let obstacle_names: Vec<String> = (0..n_obstacles).map(|j| format!("obstacle_{j}")).collect();
    let obstacle_normals: Vec<Vec<Vec<[f32; 3]>>> = (0..n_obstacles)
        .map(|j| {
            let tris = &first.obstacles[j].mesh.triangles;
            frames
                .iter()
                .map(|f| vertex_normals(&f.obstacles[j].mesh.positions, tris))
                .collect()
        })
        .collect();
    for j in 0..n_obstacles {
        meshes.push(GltfMesh {
            name: &obstacle_names[j],
            color: linear(OBSTACLE_COLOR),
            topology: Topology::Triangles(&first.obstacles[j].mesh.triangles),
            positions: frames.iter().map(|f| &f.obstacles[j].mesh.positions[..]).collect(),
            normals: obstacle_normals[j].iter().map(|n| &n[..]).collect(),
        });
    }
    write_glb(path, &meshes, &times)
}
