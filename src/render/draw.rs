//! Drawing scene items into a [`Frame`]: shaded meshes (smooth, two-sided) and hair lines.
//!
//! Meshes: each vertex goes to view space once; each triangle is clipped to the near plane,
//! projected and scanned, and every visible sample interpolates the world position and smooth
//! normal perspective-correctly and is lit by [`Lights::surface`]. Whether a triangle shows its
//! back is decided from its geometric normal `(p1 - p0) × (p2 - p0)` against the direction to
//! the eye; a back face flips the interpolated normal and uses [`back_tint`].
//!
//! Lines: each segment of a polyline is clipped, projected and scanned as a capsule whose width
//! is given in output pixels (times the supersampling factor), lit by [`Lights::hair`] with the
//! segment's tangent; strands darken slightly toward the root so bundles show depth.

use super::camera::View;
use super::math::{cross, dot, is_finite3, lerp3, normalize, normalize_or, scale, sub};
use super::prep::PreparedMesh;
use super::raster::Frame;
use super::raster::{clip_segment, clip_triangle, raster_segment, raster_triangle, ClipVertex};
use super::shade::{back_tint, color_to_linear, to_eye, Lights};
use super::shadow::ShadowMap;
use super::LineItem;

/// Everything a draw call needs besides the item.
pub(crate) struct Context<'a> {
    /// The camera.
    pub view: View,
    /// The light rig.
    pub lights: Lights,
    /// Shadows cast toward the key light, if enabled.
    pub shadow: Option<&'a ShadowMap>,
}

impl Context<'_> {
    #[inline]
    fn shadow_at(&self, p: [f32; 3], n: [f32; 3]) -> f32 {
        self.shadow.map_or(1.0, |s| s.visibility(p, n))
    }
}

/// Draws a prepared mesh.
pub(crate) fn draw_mesh(frame: &mut Frame, ctx: &Context<'_>, mesh: &PreparedMesh<'_>) {
    let view = &ctx.view;
    let front = mesh.color;
    let back = back_tint(front);
    let view_pos: Vec<[f32; 3]> = mesh.positions.iter().map(|&p| view.view_coords(p)).collect();
    let (w, h) = (frame.width, frame.height);
    for t in &mesh.triangles {
        let [i0, i1, i2] = t.map(|i| i as usize);
        let (p0, p1, p2) = (mesh.positions[i0], mesh.positions[i1], mesh.positions[i2]);
        let face = normalize_or(cross(sub(p1, p0), sub(p2, p0)), [0.0, 1.0, 0.0]);
        let is_back = dot(face, sub(view.eye, p0)) < 0.0;
        let base = if is_back { back } else { front };
        let sign = if is_back { -1.0 } else { 1.0 };
        let corner = |i: usize| {
            let p = mesh.positions[i];
            let n = mesh.normals[i];
            let n = if n == [0.0; 3] { face } else { n };
            ClipVertex {
                view: view_pos[i],
                attr: [p[0], p[1], p[2], n[0], n[1], n[2]],
            }
        };
        let tri = [corner(i0), corner(i1), corner(i2)];
        if tri.iter().all(|v| v.view[2] < view.near) {
            continue;
        }
        let (poly, count) = clip_triangle(tri, view.near);
        let mut screen = [[0.0f32; 3]; 4];
        for (s, v) in screen.iter_mut().zip(&poly[..count]) {
            *s = view.project(v.view);
        }
        for k in 1..count.saturating_sub(1) {
            let (a, b, c) = (&poly[0], &poly[k], &poly[k + 1]);
            let s = [screen[0], screen[k], screen[k + 1]];
            let color = &mut frame.color;
            raster_triangle(w, h, &mut frame.depth, s, |i, wt| {
                let mut attr = [0.0f32; 6];
                for (j, v) in attr.iter_mut().enumerate() {
                    *v = wt[0] * a.attr[j] + wt[1] * b.attr[j] + wt[2] * c.attr[j];
                }
                let p = [attr[0], attr[1], attr[2]];
                let n = scale(normalize_or([attr[3], attr[4], attr[5]], face), sign);
                let v = to_eye(view.eye, p);
                let shadow = ctx.shadow_at(p, n);
                color[i] = ctx.lights.surface(n, v, base, shadow);
            });
        }
    }
}

/// Draws a polyline item whose `width_px` has been checked to be positive, at `supersample`
/// samples per output pixel.
pub(crate) fn draw_line(frame: &mut Frame, ctx: &Context<'_>, line: &LineItem, supersample: u32) {
    let view = &ctx.view;
    let base = color_to_linear(line.color);
    let half = (0.5 * line.width_px * supersample as f32).max(0.5);
    let segments = line.points.len().saturating_sub(1);
    let (w, h) = (frame.width, frame.height);
    for k in 0..segments {
        let (pa, pb) = (line.points[k], line.points[k + 1]);
        if !(is_finite3(pa) && is_finite3(pb)) {
            continue;
        }
        let Some(tangent) = normalize(sub(pb, pa)) else {
            continue;
        };
        let va = ClipVertex {
            view: view.view_coords(pa),
            attr: [k as f32],
        };
        let vb = ClipVertex {
            view: view.view_coords(pb),
            attr: [k as f32 + 1.0],
        };
        let Some((ca, cb)) = clip_segment(va, vb, view.near) else {
            continue;
        };
        let (sa, sb) = (view.project(ca.view), view.project(cb.view));
        let mid = lerp3(pa, pb, 0.5);
        let v = to_eye(view.eye, mid);
        let color = &mut frame.color;
        raster_segment(w, h, &mut frame.depth, sa, sb, half, |i, t| {
            let along = (ca.attr[0] + (cb.attr[0] - ca.attr[0]) * t) / segments as f32;
            let shade = 0.65 + 0.35 * along;
            color[i] = ctx.lights.hair(tangent, v, base, shade);
        });
    }
}
