//! Entry points shared by the fuzz targets (`fuzz/`) and the corpus replay test
//! (`tests/fuzz_corpus.rs`), so CI runs the saved corpus through exactly what the fuzzers run.
//! Each returns normally for every input; a panic is a bug.

use crate::model::cloth::{ClothDesc, PinSpec};
use crate::model::effects::{Effects, Wind};
use crate::model::fabric::Fabric;
use crate::model::params::{Backend, Method, SolverParams};
use crate::model::self_collision::{Response, SelfBroadphase, SelfCollision};
use crate::model::shapes::Shape;
use crate::obstacles::obstacle::Obstacle;
use crate::scene::Scene;
use crate::World;

/// Parses arbitrary bytes as a scene; if it parses, builds the world and runs a few steps when
/// the scene is small.
pub fn scene_bytes(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(scene) = Scene::parse(text, "fuzz.toml") else { return };
    if !small_enough(&scene) {
        return;
    }
    if let Ok(mut w) = scene.world() {
        let dt = w.params().dt;
        for _ in 0..3 {
            if w.step(dt).is_err() {
                break;
            }
        }
        let _ = scene.to_toml();
    }
}

/// Bounds the work: huge but valid scenes are legitimate, just not for a fuzzer.
fn small_enough(scene: &Scene) -> bool {
    let c = scene.memory_counts();
    let faces: u64 = scene
        .obstacle
        .iter()
        .filter_map(|o| o.get_ref().dress_form.map(|d| d.0 as u64))
        .sum();
    let cells: u64 = scene
        .obstacle
        .iter()
        .filter_map(|o| o.get_ref().cells.map(|k| k.iter().map(|c| c.0 as u64).product::<u64>()))
        .sum();
    c.particles <= 20_000
        && c.obstacles <= 16
        && faces <= 20_000
        && cells <= 1_000_000
        && scene.solver.substeps.0 <= 64
        && scene.solver.iterations.0 <= 64
}

/// Decodes arbitrary bytes as a checkpoint twice: as they are, and with a valid hash appended
/// (so the fuzzer reaches the length and scene checks behind the hash). A checkpoint that
/// decodes is resumed as `weft run --resume` does (scene parsed, world built, state restored)
/// and stepped when small.
pub fn checkpoint_bytes(data: &[u8]) {
    use crate::world::checkpoint::{fnv1a, Checkpoint};
    let mut hashed = data.to_vec();
    hashed.extend_from_slice(&fnv1a(data).to_le_bytes());
    for bytes in [data, &hashed[..]] {
        let Ok(c) = Checkpoint::from_bytes(bytes) else { continue };
        let Ok(scene) = Scene::parse(&c.scene, "fuzz-checkpoint") else {
            continue;
        };
        if !small_enough(&scene) {
            continue;
        }
        let Ok(mut w) = scene.world() else { continue };
        if w.restore(&c).is_err() {
            continue;
        }
        let dt = w.params().dt;
        for _ in 0..2 {
            if w.step(dt).is_err() {
                break;
            }
        }
        let _ = w.checkpoint(&c.scene).to_bytes();
    }
}

/// Reads numbers from a byte string, cycling through it; empty input gives zeros.
struct Bytes<'a> {
    data: &'a [u8],
    at: usize,
}

impl Bytes<'_> {
    fn u8(&mut self) -> u8 {
        if self.data.is_empty() {
            return 0;
        }
        let b = self.data[self.at % self.data.len()];
        self.at += 1;
        b
    }
    fn f32(&mut self) -> f32 {
        f32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }
    fn one_in(&mut self, k: u8) -> bool {
        self.u8().is_multiple_of(k)
    }
    fn small(&mut self, max: u8) -> u32 {
        (self.u8() % max) as u32
    }
}

/// Builds a small world from arbitrary bytes (any float, including NaN, infinities and
/// subnormals, in every parameter and initial state), with any of the four methods, an optional
/// sphere obstacle and optional self-collision (each response and broadphase), and steps it. Bad parameters must be
/// errors; accepted worlds must step without panicking and never expose non-finite state.
pub fn step_bytes(data: &[u8]) {
    let mut b = Bytes { data, at: 0 };
    let params = SolverParams {
        dt: b.f32(),
        substeps: b.small(6),
        iterations: b.small(4),
        threads: b.small(3) as usize,
        backend: if b.one_in(2) { Backend::Simd } else { Backend::Scalar },
        method: match b.u8() % 4 {
            0 => Method::Xpbd,
            1 => Method::SymplecticEuler,
            2 => Method::Leapfrog,
            _ => Method::ImplicitEuler,
        },
        guard: true,
        ..SolverParams::default()
    };
    let effects = Effects {
        gravity: b.one_in(2).then(|| [b.f32(), b.f32(), b.f32()]),
        drag: b.one_in(3).then(|| b.f32()),
        wind: b.one_in(3).then(|| Wind {
            velocity: [b.f32(), b.f32(), b.f32()],
            gust: b.f32(),
            ..Wind::default()
        }),
    };
    let Ok(mut world) = World::new(params.clone(), effects) else {
        return;
    };
    let fabric = Fabric {
        mass: b.f32(),
        stretch_compliance: b.f32(),
        shear_compliance: b.f32(),
        bend_compliance: b.f32(),
        damping: b.f32(),
        thickness: b.f32(),
        dt: 0.01,
    };
    let desc = ClothDesc {
        rows: b.small(12),
        cols: b.small(12),
        spacing: b.f32(),
        origin: [b.f32(), b.f32(), b.f32()],
        u: [b.f32(), b.f32(), b.f32()],
        v: [b.f32(), b.f32(), b.f32()],
        fabric,
        pins: match b.u8() % 4 {
            0 => vec![],
            1 => vec![PinSpec::FirstRowCorners],
            2 => vec![PinSpec::Row(b.small(12))],
            _ => vec![PinSpec::Indices(vec![b.small(200), b.small(200)])],
        },
        shear: b.one_in(2),
        bend: b.one_in(2),
        tethers: b.one_in(2).then(|| b.f32()),
    };
    if world.add_cloth(&desc).is_err() {
        return;
    }
    if b.one_in(2) {
        let shape = Shape::Sphere {
            center: [b.f32(), b.f32(), b.f32()],
            radius: b.f32(),
        };
        if let Ok(o) = Obstacle::shape(shape) {
            let _ = world.add_obstacle(o);
        }
    }
    if b.one_in(2) {
        let config = SelfCollision {
            distance: b.one_in(2).then(|| b.f32()),
            friction: b.f32(),
            response: match b.u8() % 3 {
                0 => Response::Pbd,
                1 => Response::MovementSpeed,
                _ => Response::Vccpbd,
            },
            broadphase: if b.one_in(2) {
                SelfBroadphase::Hash
            } else {
                SelfBroadphase::AabbTree
            },
            measure: b.one_in(2),
            travel: if b.one_in(2) { b.f32() } else { 1.0 },
        };
        let _ = world.set_self_collision(Some(config));
    }
    let n = world.particle_count();
    let v: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| b.f32()).collect());
    let _ = world.set_velocities([&v[0], &v[1], &v[2]]);
    for _ in 0..4 {
        match world.step(params.dt) {
            Ok(()) => {}
            Err(_) => break,
        }
        let finite = world
            .positions()
            .iter()
            .chain(world.velocities().iter())
            .all(|a| a.iter().all(|x| x.is_finite()));
        assert!(finite, "a step exposed a non-finite value");
    }
    let _ = world.metrics();
}

/// Loads arbitrary bytes as an OBJ mesh; when it loads, builds all three broadphases and asks
/// each for the contact of a few segments (they must agree, as the proptests demand).
pub fn obj_bytes(data: &[u8]) {
    use crate::obstacles::mesh::broadphase::bvh::Bvh;
    use crate::obstacles::mesh::broadphase::grid::UniformGrid;
    use crate::obstacles::mesh::broadphase::hash::FaceHash;
    use crate::obstacles::mesh::narrow::mesh_contact;
    use crate::obstacles::mesh::TriMesh;
    let Ok((mesh, _report)) = TriMesh::from_obj_reader(&mut std::io::Cursor::new(data), "fuzz.obj") else {
        return;
    };
    if mesh.face_count() > 5_000 {
        return;
    }
    let (lo, hi) = mesh.bounds();
    let grid = UniformGrid::auto(&mesh);
    let bvh = Bvh::new(&mesh);
    let hash = FaceHash::auto(&mesh);
    let mid = [0, 1, 2].map(|k| 0.5 * lo[k] + 0.5 * hi[k]);
    let above = [mid[0], hi[1] + 1.0, mid[2]];
    let segments = [(above, mid), (lo, hi), (hi, lo), (mid, mid)];
    for (x, p) in segments {
        let reference = grid.as_ref().ok().map(|g| mesh_contact(&mesh, g, x, p, 0.01));
        let c = mesh_contact(&mesh, &bvh, x, p, 0.01);
        if let Some(r) = &reference {
            assert_eq!(r, &c, "grid and BVH disagree");
        }
        if let Ok(h) = &hash {
            let c = mesh_contact(&mesh, h, x, p, 0.01);
            if let Some(r) = &reference {
                assert_eq!(r, &c, "grid and hash disagree");
            }
        }
    }
}
