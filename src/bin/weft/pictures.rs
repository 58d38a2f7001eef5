//! Turning world states into pictures.

use weft::collide::obstacles::Geometry;
use weft::collide::shapes::Shape;
use weft::render::{self, shapes, Camera, Image, MeshItem, RenderOptions, RenderScene};

/// Colours given to successive cloths.
const CLOTH_COLORS: [[u8; 3]; 4] = [[196, 64, 58], [58, 110, 190], [224, 170, 60], [90, 160, 100]];

/// Colour of obstacles: a neutral grey.
const OBSTACLE_COLOR: [u8; 3] = [170, 170, 165];

/// One recorded frame: interleaved positions and the obstacles where they were.
pub struct Frame {
    pub positions: Vec<[f32; 3]>,
    pub obstacles: Vec<MeshItem>,
}

/// Render meshes of the world's obstacles at the world's current time. Planes are drawn as a
/// square as large as the cloth's extent (twice, at least 1 m).
pub fn obstacle_items(world: &weft::World) -> Vec<MeshItem> {
    let [x, y, z] = world.positions();
    let extent = [x, y, z]
        .iter()
        .map(|a| {
            let (lo, hi) = a
                .iter()
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), v| (l.min(*v), h.max(*v)));
            if hi >= lo {
                hi - lo
            } else {
                0.0
            }
        })
        .fold(0.0f32, f32::max);
    let half = extent.max(1.0);
    world
        .obstacles()
        .iter()
        .map(|o| {
            let shape = match (o.shape_at(world.time()), o.geometry()) {
                (Some(Shape::Plane { point, normal }), _) => shapes::plane_quad(point, normal, half),
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
            MeshItem::from_shape(shape, OBSTACLE_COLOR)
        })
        .collect()
}

/// The render scene of a frame.
pub fn scene_of(world: &weft::World, frame: &Frame) -> RenderScene {
    let mut meshes = Vec::new();
    for (k, c) in world.cloths().iter().enumerate() {
        let first = c.first as usize;
        let count = (c.rows * c.cols) as usize;
        let tris = &world.triangles()[c.first_triangle as usize..(c.first_triangle + c.triangle_count) as usize];
        meshes.push(MeshItem {
            positions: frame.positions[first..first + count].to_vec(),
            triangles: tris.iter().map(|t| [t[0] - c.first, t[1] - c.first, t[2] - c.first]).collect(),
            color: CLOTH_COLORS[k % CLOTH_COLORS.len()],
        });
    }
    meshes.extend(frame.obstacles.iter().cloned());
    RenderScene {
        meshes,
        lines: Vec::new(),
        background: render::DEFAULT_BACKGROUND,
    }
}

/// A camera that frames every frame (so the contact sheet and GIF share one view).
pub fn shared_camera(
    world: &weft::World,
    frames: &[Frame],
    aspect: f32,
    eye: Option<[f32; 3]>,
    target: Option<[f32; 3]>,
) -> Option<Camera> {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for f in frames {
        if let Some((a, b)) = scene_of(world, f).bounds() {
            for k in 0..3 {
                lo[k] = lo[k].min(a[k]);
                hi[k] = hi[k].max(b[k]);
            }
        }
    }
    if !lo[0].is_finite() {
        return None;
    }
    let mut cam = Camera::framing_for_aspect(lo, hi, aspect);
    if let Some(t) = target {
        cam.target = t;
    }
    if let Some(e) = eye {
        cam.eye = e;
    }
    Some(cam)
}

/// Renders one frame.
pub fn render_frame(world: &weft::World, frame: &Frame, width: u32, height: u32, camera: Option<Camera>) -> weft::Result<Image> {
    let opts = RenderOptions {
        width,
        height,
        camera,
        ..RenderOptions::default()
    };
    render::render(&scene_of(world, frame), &opts)
}
