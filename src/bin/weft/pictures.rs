//! Turning world states into pictures.

use weft::render::{self, Camera, Image, MeshItem, RenderOptions, RenderScene};

/// Colours given to successive cloths.
const CLOTH_COLORS: [[u8; 3]; 4] = [[196, 64, 58], [58, 110, 190], [224, 170, 60], [90, 160, 100]];

/// One recorded frame: interleaved positions.
pub struct Frame {
    pub positions: Vec<[f32; 3]>,
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
