//! Scan conversion: triangles and thick line segments into a colour + depth buffer.
//!
//! Triangles use edge functions over their bounding box (Pineda 1988): for screen points
//! `a, b, c` with doubled signed area `A = E(a, b, c)`, `E(u, v, p) = (v - u) × (p - u)`, a pixel
//! centre `p` is inside when `E(b, c, p)`, `E(c, a, p)`, `E(a, b, p)` are all `>= 0` (after
//! orienting the triangle so `A > 0`), and these divided by `A` are its screen-space
//! barycentrics `λ`. Depth is `1/z`, which is linear in screen space: `1/z = Σ λ_k / z_k`; a
//! larger value is nearer. Perspective-correct weights for attributes are `λ_k (1/z_k) / (1/z)`.
//!
//! Geometry crossing the near plane is clipped in view space first (a triangle becomes a polygon
//! of up to four corners, drawn as a fan), so nothing behind the camera is ever projected.
//!
//! Lines are capsules in screen space: a pixel is covered when its distance to the projected
//! segment is at most half the width; its depth interpolates `1/z` along the segment.

/// The supersampled working picture: linear colour and `1/z` depth per sample.
pub(crate) struct Frame {
    /// Width in samples.
    pub width: usize,
    /// Height in samples.
    pub height: usize,
    /// Linear RGB per sample.
    pub color: Vec<[f32; 3]>,
    /// `1/z` per sample; 0 is infinitely far.
    pub depth: Vec<f32>,
}

impl Frame {
    /// A frame of `width` x `height` samples with every depth at infinity.
    pub fn new(width: usize, height: usize) -> Frame {
        Frame {
            width,
            height,
            color: vec![[0.0; 3]; width * height],
            depth: vec![0.0; width * height],
        }
    }
}

/// A view-space vertex with `N` attributes to interpolate.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ClipVertex<const N: usize> {
    /// View-space position (z = depth).
    pub view: [f32; 3],
    /// Attributes.
    pub attr: [f32; N],
}

fn lerp_vertex<const N: usize>(a: &ClipVertex<N>, b: &ClipVertex<N>, t: f32) -> ClipVertex<N> {
    let mut out = *a;
    for k in 0..3 {
        out.view[k] = a.view[k] + (b.view[k] - a.view[k]) * t;
    }
    for k in 0..N {
        out.attr[k] = a.attr[k] + (b.attr[k] - a.attr[k]) * t;
    }
    out
}

/// Clips a triangle to `z >= near` (Sutherland-Hodgman with one plane). Returns the corners
/// of the kept polygon (0, 3 or 4) and their count.
pub(crate) fn clip_triangle<const N: usize>(tri: [ClipVertex<N>; 3], near: f32) -> ([ClipVertex<N>; 4], usize) {
    let mut out = [tri[0]; 4];
    let mut count = 0;
    for i in 0..3 {
        let (cur, next) = (&tri[i], &tri[(i + 1) % 3]);
        let (cin, nin) = (cur.view[2] >= near, next.view[2] >= near);
        if cin {
            out[count] = *cur;
            count += 1;
        }
        if cin != nin {
            let t = (near - cur.view[2]) / (next.view[2] - cur.view[2]);
            out[count] = lerp_vertex(cur, next, t);
            out[count].view[2] = near;
            count += 1;
        }
    }
    (out, count)
}

/// Clips a segment to `z >= near`; `None` when it lies wholly behind the plane.
pub(crate) fn clip_segment<const N: usize>(a: ClipVertex<N>, b: ClipVertex<N>, near: f32) -> Option<(ClipVertex<N>, ClipVertex<N>)> {
    match (a.view[2] >= near, b.view[2] >= near) {
        (true, true) => Some((a, b)),
        (false, false) => None,
        (ain, _) => {
            let t = (near - a.view[2]) / (b.view[2] - a.view[2]);
            let mut m = lerp_vertex(&a, &b, t);
            m.view[2] = near;
            Some(if ain { (a, m) } else { (m, b) })
        }
    }
}

/// Inclusive pixel range covered by `[lo, hi]` on an axis of `n` pixels (pixel centres at
/// `i + 0.5`), or `None` when it misses the image.
#[inline]
fn span(lo: f32, hi: f32, n: usize) -> Option<(usize, usize)> {
    let first = (lo - 0.5).ceil().max(0.0);
    let last = (hi - 0.5).floor().min(n as f32 - 1.0);
    (first <= last).then_some((first as usize, last as usize))
}

/// Rasterizes a screen-space triangle (`[x, y, 1/z]` corners) against `depth`. For every sample
/// that passes the depth test, the depth is written and `on_pixel(index, weights)` is called
/// with perspective-correct weights of the three corners in their given order.
#[inline]
pub(crate) fn raster_triangle(width: usize, height: usize, depth: &mut [f32], s: [[f32; 3]; 3], mut on_pixel: impl FnMut(usize, [f32; 3])) {
    let [a, b0, c0] = s;
    let area = (b0[0] - a[0]) * (c0[1] - a[1]) - (b0[1] - a[1]) * (c0[0] - a[0]);
    if area == 0.0 || !area.is_finite() {
        return;
    }
    let flip = area < 0.0;
    let (b, c) = if flip { (c0, b0) } else { (b0, c0) };
    let inv_area = 1.0 / area.abs();
    let Some((x0, x1)) = span(a[0].min(b[0]).min(c[0]), a[0].max(b[0]).max(c[0]), width) else {
        return;
    };
    let Some((y0, y1)) = span(a[1].min(b[1]).min(c[1]), a[1].max(b[1]).max(c[1]), height) else {
        return;
    };
    // E(u, v, p) = (v.x - u.x)(p.y - u.y) - (v.y - u.y)(p.x - u.x); step in x is -(v.y - u.y).
    let edge = |u: [f32; 3], v: [f32; 3], px: f32, py: f32| (v[0] - u[0]) * (py - u[1]) - (v[1] - u[1]) * (px - u[0]);
    let (dx0, dx1, dx2) = (-(c[1] - b[1]), -(a[1] - c[1]), -(b[1] - a[1]));
    for y in y0..=y1 {
        let py = y as f32 + 0.5;
        let px = x0 as f32 + 0.5;
        let mut w0 = edge(b, c, px, py);
        let mut w1 = edge(c, a, px, py);
        let mut w2 = edge(a, b, px, py);
        let row = y * width;
        for x in x0..=x1 {
            if w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0 {
                let (l0, l1, l2) = (w0 * inv_area, w1 * inv_area, w2 * inv_area);
                let iz = l0 * a[2] + l1 * b[2] + l2 * c[2];
                let i = row + x;
                if iz > depth[i] {
                    depth[i] = iz;
                    let r = 1.0 / iz;
                    let (p0, p1, p2) = (l0 * a[2] * r, l1 * b[2] * r, l2 * c[2] * r);
                    on_pixel(i, if flip { [p0, p2, p1] } else { [p0, p1, p2] });
                }
            }
            w0 += dx0;
            w1 += dx1;
            w2 += dx2;
        }
    }
}

/// Relative depth advantage given to lines so strands lying on a surface are not hidden by it.
const LINE_DEPTH_BIAS: f32 = 5e-4;

/// Rasterizes a thick screen-space segment (`[x, y, 1/z]` ends) with half-width `half` pixels.
/// For every covered sample that passes the depth test, the depth is written and
/// `on_pixel(index, t)` is called with the position `t` in [0, 1] along the segment.
pub(crate) fn raster_segment(
    width: usize,
    height: usize,
    depth: &mut [f32],
    a: [f32; 3],
    b: [f32; 3],
    half: f32,
    mut on_pixel: impl FnMut(usize, f32),
) {
    if !(a.iter().chain(&b).all(|v| v.is_finite()) && half.is_finite()) {
        return;
    }
    let Some((x0, x1)) = span(a[0].min(b[0]) - half, a[0].max(b[0]) + half, width) else {
        return;
    };
    let Some((y0, y1)) = span(a[1].min(b[1]) - half, a[1].max(b[1]) + half, height) else {
        return;
    };
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let inv_len2 = if len2 > 0.0 { 1.0 / len2 } else { 0.0 };
    let half2 = half * half;
    for y in y0..=y1 {
        let py = y as f32 + 0.5 - a[1];
        for x in x0..=x1 {
            let px = x as f32 + 0.5 - a[0];
            let t = ((px * dx + py * dy) * inv_len2).clamp(0.0, 1.0);
            let (ex, ey) = (px - t * dx, py - t * dy);
            if ex * ex + ey * ey <= half2 {
                let iz = a[2] + (b[2] - a[2]) * t;
                let i = y * width + x;
                if iz * (1.0 + LINE_DEPTH_BIAS) > depth[i] {
                    depth[i] = depth[i].max(iz);
                    on_pixel(i, t);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_covers_about_its_area_and_depth_keeps_the_nearest() {
        let (w, h) = (64, 64);
        let mut depth = vec![0.0; w * h];
        let mut count = 0;
        let far = [[4.0, 4.0, 0.5], [60.0, 4.0, 0.5], [4.0, 60.0, 0.5]];
        raster_triangle(w, h, &mut depth, far, |_, p| {
            assert!((p.iter().sum::<f32>() - 1.0).abs() < 1e-4);
            count += 1;
        });
        let area = 56.0 * 56.0 / 2.0;
        assert!((count as f32 - area).abs() < 60.0, "{count} vs {area}");
        // Same triangle, reversed winding and farther: nothing passes.
        let behind = [[4.0, 4.0, 0.25], [4.0, 60.0, 0.25], [60.0, 4.0, 0.25]];
        raster_triangle(w, h, &mut depth, behind, |_, _| panic!("hidden"));
        // Nearer, reversed winding: weights come back in the given corner order.
        let near = [[4.0, 4.0, 1.0], [4.0, 60.0, 1.0], [60.0, 4.0, 1.0]];
        let mut hit = 0;
        raster_triangle(w, h, &mut depth, near, |i, p| {
            if i == 5 * w + 50 {
                assert!(p[2] > p[1]); // close to corner 2 (x = 60)
            }
            hit += 1;
        });
        assert_eq!(hit, count);
    }

    #[test]
    fn degenerate_and_offscreen_triangles_draw_nothing() {
        let mut depth = vec![0.0; 100];
        let flat = [[1.0, 1.0, 1.0], [5.0, 5.0, 1.0], [9.0, 9.0, 1.0]];
        raster_triangle(10, 10, &mut depth, flat, |_, _| panic!("flat"));
        let off = [[-50.0, -50.0, 1.0], [-40.0, -50.0, 1.0], [-50.0, -40.0, 1.0]];
        raster_triangle(10, 10, &mut depth, off, |_, _| panic!("offscreen"));
        let nan = [[f32::NAN, 1.0, 1.0], [5.0, 1.0, 1.0], [1.0, 5.0, 1.0]];
        raster_triangle(10, 10, &mut depth, nan, |_, _| panic!("nan"));
    }

    #[test]
    fn near_clipping_keeps_the_front_part() {
        let v = |z: f32| ClipVertex {
            view: [0.0, z, z],
            attr: [z],
        };
        let (_, n) = clip_triangle([v(-1.0), v(-2.0), v(-3.0)], 0.1);
        assert_eq!(n, 0);
        let (poly, n) = clip_triangle([v(-1.0), v(2.0), v(3.0)], 0.1);
        assert_eq!(n, 4);
        assert!(poly[..n].iter().all(|p| p.view[2] >= 0.1 - 1e-6));
        let (_, n) = clip_triangle([v(-1.0), v(-2.0), v(3.0)], 0.1);
        assert_eq!(n, 3);
        let (a, b) = clip_segment(v(-1.0), v(1.0), 0.1).unwrap();
        assert_eq!((a.view[2], b.view[2]), (0.1, 1.0));
        assert!((a.attr[0] - 0.1).abs() < 1e-6);
        assert!(clip_segment(v(-1.0), v(-0.5), 0.1).is_none());
    }

    #[test]
    fn segment_covers_a_band_of_its_width() {
        let (w, h) = (40, 40);
        let mut depth = vec![0.0; w * h];
        let mut count = 0;
        raster_segment(w, h, &mut depth, [5.0, 20.0, 1.0], [35.0, 20.0, 1.0], 2.0, |_, t| {
            assert!((0.0..=1.0).contains(&t));
            count += 1;
        });
        // 30 px long, 4 px wide, plus round caps.
        assert!((110..=150).contains(&count), "{count}");
    }
}
