//! Turning world states into pictures.
//!
//! Cloth is drawn as its triangles, or (with `--nurbs-surface` / `[output] cloth_surface =
//! "nurbs"`) as a NURBS surface whose control points are the cloth's particle grid. Strands are
//! drawn as smooth NURBS curves through their simulated points (root and tip exact, the rest
//! smoothed, as in the NURBS thesis), and each scalp as a shaded ellipsoid mesh. The default
//! camera frames what moves ([`framed_box`]): the cloths, the strands with their scalps, and the
//! bounded obstacles that come near them; an infinite plane is drawn as a quad under the cloth
//! but never framed, so a small cloth on a ground plane fills the picture.

use weft::model::shapes::Shape;
use weft::obstacles::Geometry;
use weft::render::{self, shapes, Camera, Image, LineItem, MeshItem, RenderOptions, RenderScene};
use weft::strands::nurbs::{NurbsCurve, NurbsSurface};

/// Colour of obstacles: a neutral grey.
pub const OBSTACLE_COLOR: [u8; 3] = [170, 170, 165];

/// Colours given to successive cloths.
pub const CLOTH_COLORS: [[u8; 3]; 4] = [[196, 64, 58], [58, 110, 190], [224, 170, 60], [90, 160, 100]];

/// Base hair colours of successive strand groups (each strand varies around it).
pub const HAIR_COLORS: [[u8; 3]; 3] = [[92, 58, 32], [180, 140, 80], [40, 30, 24]];

/// Scalp (skin) colour.
pub const SCALP_COLOR: [u8; 3] = [214, 172, 140];

/// Degree of the drawn NURBS curves and surfaces (cubic).
const DRAW_DEGREE: usize = 3;

/// Samples per simulated point along a drawn strand.
const STRAND_SAMPLES_PER_POINT: usize = 3;

/// Surface samples per particle along each grid direction (capped at [`MAX_SURFACE_SAMPLES`]).
const SURFACE_SAMPLES_PER_POINT: usize = 2;
const MAX_SURFACE_SAMPLES: usize = 400;

/// How a frame is drawn.
#[derive(Clone, Copy, Debug, Default)]
pub struct Style {
    /// Draw each cloth as a NURBS surface over its particle grid instead of its triangles.
    pub nurbs_surface: bool,
}

/// One recorded frame: interleaved positions (and normals when a glTF file is asked for),
/// the simulated time, and the obstacles where they were.
pub struct Frame {
    pub positions: Vec<[f32; 3]>,
    /// Area-weighted vertex normals (`World::read_normals`), or empty.
    pub normals: Vec<[f32; 3]>,
    pub time: f64,
    pub obstacles: Vec<Obstacle>,
}

/// An obstacle's drawn mesh; `plane` marks an infinite plane, drawn as a finite quad but never
/// framed by the camera.
#[derive(Clone)]
pub struct Obstacle {
    pub mesh: MeshItem,
    pub plane: bool,
}

/// Where infinite planes are drawn: a square of half side `half` around the point of the plane
/// nearest `center`.
#[derive(Clone, Copy, Debug)]
pub struct PlaneSpan {
    pub center: [f32; 3],
    pub half: f32,
}

/// A plane span for the world's particles as they are now: centred under their bounding box,
/// half as wide as its largest side, at least 1 m.
pub fn plane_span(world: &weft::World) -> PlaneSpan {
    let [x, y, z] = world.positions();
    let mut center = [0.0f32; 3];
    let mut extent = 0.0f32;
    for (k, a) in [x, y, z].iter().enumerate() {
        let (lo, hi) = a
            .iter()
            .filter(|v| v.is_finite())
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), v| (l.min(*v), h.max(*v)));
        if hi >= lo {
            center[k] = 0.5 * (lo + hi);
            extent = extent.max(hi - lo);
        }
    }
    PlaneSpan {
        center,
        half: extent.max(1.0),
    }
}

/// Render meshes of the world's obstacles at the world's current time. Planes are drawn as a
/// square given by `span`.
pub fn obstacle_items(world: &weft::World, span: PlaneSpan) -> Vec<Obstacle> {
    world
        .obstacles()
        .iter()
        .map(|o| {
            let mut plane = false;
            let shape = match (o.shape_at(world.time()), o.geometry()) {
                (Some(Shape::Plane { point, normal }), _) => {
                    plane = true;
                    let n = normal;
                    let nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
                    let d = [0, 1, 2].map(|k| span.center[k] - point[k]);
                    let s = if nn > 0.0 {
                        (d[0] * n[0] + d[1] * n[1] + d[2] * n[2]) / nn
                    } else {
                        0.0
                    };
                    let foot = [0, 1, 2].map(|k| span.center[k] - s * n[k]);
                    shapes::plane_quad(foot, normal, span.half)
                }
                (Some(Shape::Sphere { center, radius }), _) => shapes::uv_sphere(center, radius, 48),
                (Some(Shape::Capsule { a, b, radius }), _) => shapes::capsule(a, b, radius, 32),
                (Some(Shape::Box { center, half, axes }), _) => {
                    let (v, t) = shapes::box_mesh([0.0; 3], half);
                    let v = v
                        .iter()
                        .map(|l| [0, 1, 2].map(|k| center[k] + axes[0][k] * l[0] + axes[1][k] * l[1] + axes[2][k] * l[2]))
                        .collect();
                    (v, t)
                }
                (None, Geometry::Mesh(m)) => (m.mesh().vertices().to_vec(), m.mesh().faces().to_vec()),
                _ => (Vec::new(), Vec::new()),
            };
            Obstacle {
                mesh: MeshItem::from_shape(shape, OBSTACLE_COLOR),
                plane,
            }
        })
        .collect()
}

fn columns(points: &[[f32; 3]]) -> [Vec<f32>; 3] {
    [0, 1, 2].map(|k| points.iter().map(|p| p[k]).collect())
}

/// A cheap deterministic shade variation in `[-1, 1]` per strand.
fn jitter(s: u32) -> f32 {
    let h = s.wrapping_mul(0x9E37_79B9).rotate_left(13).wrapping_mul(0x85EB_CA6B);
    (h >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
}

fn cloth_mesh(world: &weft::World, frame: &Frame, k: usize, style: Style) -> weft::Result<MeshItem> {
    let c = &world.cloths()[k];
    let first = c.first as usize;
    let count = (c.rows * c.cols) as usize;
    let color = CLOTH_COLORS[k % CLOTH_COLORS.len()];
    let pts = &frame.positions[first..first + count];
    if style.nurbs_surface && c.rows >= 2 && c.cols >= 2 {
        let [x, y, z] = columns(pts);
        let (rows, cols) = (c.rows as usize, c.cols as usize);
        let sheet = NurbsSurface::sheet(rows, cols, &x, &y, &z, DRAW_DEGREE)?;
        let ru = (rows * SURFACE_SAMPLES_PER_POINT).min(MAX_SURFACE_SAMPLES);
        let rv = (cols * SURFACE_SAMPLES_PER_POINT).min(MAX_SURFACE_SAMPLES);
        let m = sheet.sample(ru, rv)?;
        let positions = (0..m.x.len()).map(|i| [m.x[i], m.y[i], m.z[i]]).collect();
        return Ok(MeshItem {
            positions,
            triangles: m.triangles,
            color,
        });
    }
    let tris = &world.triangles()[c.first_triangle as usize..(c.first_triangle + c.triangle_count) as usize];
    Ok(MeshItem {
        positions: pts.to_vec(),
        triangles: tris.iter().map(|t| [t[0] - c.first, t[1] - c.first, t[2] - c.first]).collect(),
        color,
    })
}

/// Strands of every group as smooth curves, and the scalps as meshes.
fn hair(world: &weft::World, frame: &Frame, meshes: &mut Vec<MeshItem>, lines: &mut Vec<LineItem>) -> weft::Result<()> {
    for (k, g) in world.strands().iter().enumerate() {
        let sc = &g.scalp;
        let (pos, tris) = shapes::uv_sphere([0.0; 3], 1.0, 64);
        let pos = pos.iter().map(|p| [0, 1, 2].map(|a| sc.center[a] + p[a] * sc.radii[a])).collect();
        meshes.push(MeshItem {
            positions: pos,
            triangles: tris,
            color: SCALP_COLOR,
        });
        let base = HAIR_COLORS[k % HAIR_COLORS.len()];
        let samples = g.points as usize * STRAND_SAMPLES_PER_POINT;
        for s in 0..g.count {
            let [x, y, z] = columns(&frame.positions[g.strand_range(s)]);
            let curve = NurbsCurve::strand(&x, &y, &z, DRAW_DEGREE)?.sample(samples)?;
            let shade = 1.0 + 0.25 * jitter(s);
            lines.push(LineItem {
                points: (0..samples).map(|i| [curve.x[i], curve.y[i], curve.z[i]]).collect(),
                color: base.map(|c| (c as f32 * shade).clamp(0.0, 255.0) as u8),
                width_px: 1.0,
            });
        }
    }
    Ok(())
}

/// What moves in a frame: the cloths and the strands with their scalps.
fn subject_of(world: &weft::World, frame: &Frame, style: Style) -> weft::Result<RenderScene> {
    let mut meshes = Vec::new();
    let mut lines = Vec::new();
    for k in 0..world.cloths().len() {
        meshes.push(cloth_mesh(world, frame, k, style)?);
    }
    hair(world, frame, &mut meshes, &mut lines)?;
    Ok(RenderScene {
        meshes,
        lines,
        background: render::DEFAULT_BACKGROUND,
    })
}

/// The render scene of a frame.
pub fn scene_of(world: &weft::World, frame: &Frame, style: Style) -> weft::Result<RenderScene> {
    let mut scene = subject_of(world, frame, style)?;
    scene.meshes.extend(frame.obstacles.iter().map(|o| o.mesh.clone()));
    Ok(scene)
}

/// Grows the box `(lo, hi)` to hold `(a, b)`.
fn grow(lo: &mut [f32; 3], hi: &mut [f32; 3], (a, b): ([f32; 3], [f32; 3])) {
    for k in 0..3 {
        lo[k] = lo[k].min(a[k]);
        hi[k] = hi[k].max(b[k]);
    }
}

/// Bounding box of a mesh's finite vertices.
fn mesh_bounds(m: &MeshItem) -> Option<([f32; 3], [f32; 3])> {
    RenderScene {
        meshes: vec![m.clone()],
        lines: Vec::new(),
        background: render::DEFAULT_BACKGROUND,
    }
    .bounds()
}

/// How close (as a fraction of the size of what moves, and at least [`NEAR_MIN_M`]) a bounded
/// obstacle must come to be framed with it.
const NEAR_FRACTION: f32 = 0.1;
const NEAR_MIN_M: f32 = 0.02;

/// The box the default camera frames over all `frames`: the cloths and strands (with their
/// scalps), grown by every bounded obstacle that comes within [`NEAR_FRACTION`] of their size;
/// never an infinite plane. With nothing that moves, the bounded obstacles; with none of those
/// either, everything drawn.
pub fn framed_box(world: &weft::World, frames: &[Frame], style: Style) -> weft::Result<Option<([f32; 3], [f32; 3])>> {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for f in frames {
        if let Some(b) = subject_of(world, f, style)?.bounds() {
            grow(&mut lo, &mut hi, b);
        }
    }
    let bounded = || frames.iter().flat_map(|f| f.obstacles.iter()).filter(|o| !o.plane);
    if lo[0].is_finite() {
        let size = (0..3).map(|k| hi[k] - lo[k]).fold(0.0f32, f32::max);
        let margin = (NEAR_FRACTION * size).max(NEAR_MIN_M);
        let (slo, shi) = (lo, hi);
        for o in bounded() {
            if let Some((a, b)) = mesh_bounds(&o.mesh) {
                if (0..3).all(|k| a[k] <= shi[k] + margin && b[k] >= slo[k] - margin) {
                    grow(&mut lo, &mut hi, (a, b));
                }
            }
        }
    } else {
        for o in bounded() {
            if let Some(b) = mesh_bounds(&o.mesh) {
                grow(&mut lo, &mut hi, b);
            }
        }
        if !lo[0].is_finite() {
            for f in frames {
                if let Some(b) = scene_of(world, f, style)?.bounds() {
                    grow(&mut lo, &mut hi, b);
                }
            }
        }
    }
    Ok(lo[0].is_finite().then_some((lo, hi)))
}

/// A camera that frames [`framed_box`] over every frame (so the contact sheet and GIF share
/// one view), unless the scene gives the eye or target.
pub fn shared_camera(
    world: &weft::World,
    frames: &[Frame],
    aspect: f32,
    eye: Option<[f32; 3]>,
    target: Option<[f32; 3]>,
    style: Style,
) -> weft::Result<Option<Camera>> {
    let Some((lo, hi)) = framed_box(world, frames, style)? else {
        return Ok(None);
    };
    let mut cam = Camera::framing_for_aspect(lo, hi, aspect);
    if let Some(t) = target {
        cam.target = t;
    }
    if let Some(e) = eye {
        cam.eye = e;
    }
    Ok(Some(cam))
}

/// Renders one frame.
pub fn render_frame(
    world: &weft::World,
    frame: &Frame,
    width: u32,
    height: u32,
    camera: Option<Camera>,
    style: Style,
) -> weft::Result<Image> {
    let opts = RenderOptions {
        width,
        height,
        camera,
        ..RenderOptions::default()
    };
    render::render(&scene_of(world, frame, style)?, &opts)
}
