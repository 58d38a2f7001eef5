//! Pictures of cloth and hair: a small software rasterizer (no GPU).
//!
//! [`render`] turns a [`RenderScene`] (triangle meshes and polylines) into an [`Image`]:
//!
//! 1. **Camera.** A perspective pinhole ([`Camera`]); without one, [`Camera::framing`] picks a
//!    three-quarter view from the front and above that fits the scene's bounding box.
//! 2. **Scan conversion** into a colour + depth buffer `supersample` times larger on each axis
//!    than the output: triangles by edge functions over their bounding box with a `1/z`
//!    z-buffer and perspective-correct interpolation, clipped to the near plane; polylines as
//!    screen-space capsules of a given pixel width (see `raster`).
//! 3. **Shading** in linear light: smooth per-vertex normals, a key light, a fill light and a
//!    hemisphere ambient fixed to the camera, a soft sheen; surfaces are two-sided (a back face
//!    is lit with its normal flipped toward the eye and a darker, greyer tint); hair strands
//!    use the Kajiya-Kay tangent model (see `shade`). Optional shadows from the key light
//!    come from a filtered shadow map, which also casts a soft contact shadow on an invisible
//!    floor under the scene (see `shadow`).
//! 4. **Resolve:** each output pixel averages its `supersample²` samples (a box filter, which is
//!    the anti-aliasing) and is encoded to sRGB.
//!
//! [`contact_sheet`] tiles frames into one picture, [`write_gif`] animates them, and
//! [`shapes`] builds spheres, boxes, capsules and planes for obstacles.

mod anim;
mod camera;
#[cfg(test)]
mod demo_tests;
mod draw;
mod image;
mod math;
mod prep;
mod raster;
mod shade;
mod shadow;
pub mod shapes;
mod sheet;
#[cfg(test)]
mod tests;

pub use anim::write_gif;
pub use camera::Camera;
pub use image::{Image, BACKGROUND_TOLERANCE};
pub use sheet::contact_sheet;

use crate::{Result, WeftError};
use math::{dot, is_finite3, normalize_or};

/// A triangle mesh to draw (cloth, body, obstacle).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshItem {
    /// Vertex positions. Triangles touching a non-finite vertex are skipped.
    pub positions: Vec<[f32; 3]>,
    /// Vertex indices of each triangle; an index past `positions` is an error.
    pub triangles: Vec<[u32; 3]>,
    /// Front colour (sRGB); the back is drawn in a darker, greyer tint of it.
    pub color: [u8; 3],
}

impl MeshItem {
    /// A mesh from a [`shapes`] builder's output.
    pub fn from_shape((positions, triangles): shapes::Shape, color: [u8; 3]) -> MeshItem {
        MeshItem {
            positions,
            triangles,
            color,
        }
    }
}

/// A polyline to draw as a strand of hair.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LineItem {
    /// Points along the strand, root first. Segments touching a non-finite point are skipped.
    pub points: Vec<[f32; 3]>,
    /// Colour (sRGB).
    pub color: [u8; 3],
    /// Thickness in output pixels; must be finite and positive.
    pub width_px: f32,
}

/// Everything to draw.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderScene {
    /// Triangle meshes.
    pub meshes: Vec<MeshItem>,
    /// Polylines (hair strands).
    pub lines: Vec<LineItem>,
    /// Background colour (sRGB), drawn with a gentle vertical gradient.
    pub background: [u8; 3],
}

impl RenderScene {
    /// The axis-aligned box around every finite mesh vertex and line point, or `None` if there
    /// is none.
    pub fn bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        let points = self
            .meshes
            .iter()
            .flat_map(|m| m.positions.iter())
            .chain(self.lines.iter().flat_map(|l| l.points.iter()))
            .filter(|p| is_finite3(**p));
        let mut out: Option<([f32; 3], [f32; 3])> = None;
        for p in points {
            let (lo, hi) = out.get_or_insert((*p, *p));
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        out
    }
}

/// How to render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderOptions {
    /// Output width in pixels (at least 1).
    pub width: u32,
    /// Output height in pixels (at least 1).
    pub height: u32,
    /// Samples per pixel along each axis, 1 to 8 (2 is a good default).
    pub supersample: u32,
    /// The camera; `None` frames the scene's bounds with [`Camera::framing_for_aspect`].
    pub camera: Option<Camera>,
    /// Cast shadows from the key light onto the scene's own surfaces.
    pub shadows: bool,
    /// Darken an invisible floor under the scene (perpendicular to the camera's up) where it is
    /// in shadow: a contact cue. Needs `shadows`.
    pub ground_shadow: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: 800,
            height: 600,
            supersample: 2,
            camera: None,
            shadows: true,
            ground_shadow: true,
        }
    }
}

/// Largest supersampling factor.
pub const MAX_SUPERSAMPLE: u32 = 8;
/// Largest number of samples (output pixels times `supersample²`) one render may use; each
/// sample takes 16 bytes (colour and depth), so this bounds the working memory at 512 MiB.
pub const MAX_SAMPLES: u64 = 1 << 25;

/// The background colour the renderer uses by default: a soft blue-grey.
pub const DEFAULT_BACKGROUND: [u8; 3] = [206, 212, 222];

fn check_options(opts: &RenderOptions) -> Result<()> {
    if opts.width == 0 || opts.height == 0 {
        return Err(WeftError::param(
            "render size",
            format!("{}x{}", opts.width, opts.height),
            "width and height must be at least 1",
        ));
    }
    if !(1..=MAX_SUPERSAMPLE).contains(&opts.supersample) {
        return Err(WeftError::param(
            "supersample",
            opts.supersample,
            format!("must be between 1 and {MAX_SUPERSAMPLE}"),
        ));
    }
    let ss = opts.supersample as u64;
    let samples = opts.width as u64 * opts.height as u64 * ss * ss;
    if samples > MAX_SAMPLES {
        return Err(WeftError::param(
            "render size",
            format!("{}x{} x{}", opts.width, opts.height, opts.supersample),
            format!("needs {samples} samples, more than the limit {MAX_SAMPLES}"),
        ));
    }
    Ok(())
}

/// Renders `scene` as seen through `opts.camera` (or a framing of its bounds).
///
/// Errors: a zero size, a supersampling factor outside 1 to 8, too many samples, a bad camera,
/// a triangle index out of range, or a line width that is not positive. Non-finite vertices
/// are skipped, never an error; an empty scene gives the background.
pub fn render(scene: &RenderScene, opts: &RenderOptions) -> Result<Image> {
    check_options(opts)?;
    for (k, line) in scene.lines.iter().enumerate() {
        crate::error::positive(&format!("lines[{k}].width_px"), line.width_px)?;
    }
    let meshes = scene
        .meshes
        .iter()
        .enumerate()
        .map(|(k, m)| prep::prepare(m, k))
        .collect::<Result<Vec<_>>>()?;
    let bounds = scene.bounds();
    let aspect = opts.width as f32 / opts.height as f32;
    let camera = match (opts.camera, bounds) {
        (Some(c), _) => c,
        (None, Some((lo, hi))) => Camera::framing_for_aspect(lo, hi, aspect),
        (None, None) => Camera::framing([-0.5; 3], [0.5; 3]),
    };
    let ss = opts.supersample as usize;
    let (sw, sh) = (opts.width as usize * ss, opts.height as usize * ss);
    let view = camera.view(sw as u32, sh as u32)?;
    let world_up = normalize_or(camera.up, view.up);
    let lights = shade::Lights::for_camera(view.right, view.up, view.forward, world_up);

    let mut frame = raster::Frame::new(sw, sh);
    for y in 0..sh {
        let bg = shade::color_to_linear(shade::background_row(scene.background, (y / ss) as u32, opts.height));
        frame.color[y * sw..(y + 1) * sw].fill(bg);
    }
    let shadow_map = match bounds {
        Some((lo, hi)) if opts.shadows => {
            let lines: Vec<&[[f32; 3]]> = scene.lines.iter().map(|l| &l.points[..]).collect();
            Some(shadow::ShadowMap::build(lights.key, lo, hi, &meshes, &lines))
        }
        _ => None,
    };
    let ctx = draw::Context {
        view,
        lights,
        shadow: shadow_map.as_ref(),
    };
    for mesh in &meshes {
        draw::draw_mesh(&mut frame, &ctx, mesh);
    }
    for line in &scene.lines {
        draw::draw_line(&mut frame, &ctx, line, opts.supersample);
    }
    if let (Some(map), Some((lo, hi)), true) = (&shadow_map, bounds, opts.ground_shadow) {
        let floor = (0..8)
            .map(|k| {
                let c = [
                    if k & 1 == 0 { lo[0] } else { hi[0] },
                    if k & 2 == 0 { lo[1] } else { hi[1] },
                    if k & 4 == 0 { lo[2] } else { hi[2] },
                ];
                dot(c, world_up)
            })
            .fold(f32::INFINITY, f32::min);
        shadow::darken_ground(&mut frame, &view, map, world_up, floor);
    }
    Ok(resolve(&frame, opts.width, opts.height, ss))
}

/// Averages each `ss x ss` block of samples and encodes it to sRGB.
fn resolve(frame: &raster::Frame, width: u32, height: u32, ss: usize) -> Image {
    let enc = shade::SrgbEncoder::new();
    let (w, h) = (width as usize, height as usize);
    let mut rgb = Vec::with_capacity(3 * w * h);
    let inv = 1.0 / (ss * ss) as f32;
    for y in 0..h {
        for x in 0..w {
            let mut sum = [0.0f32; 3];
            for sy in 0..ss {
                let row = (y * ss + sy) * frame.width + x * ss;
                for c in &frame.color[row..row + ss] {
                    sum = [sum[0] + c[0], sum[1] + c[1], sum[2] + c[2]];
                }
            }
            rgb.extend(sum.map(|s| enc.encode(s * inv)));
        }
    }
    Image { width, height, rgb }
}
