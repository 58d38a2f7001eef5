//! Shadows from the key light: a shadow map (Williams 1978) with percentage-closer filtering
//! (Reeves, Salesin and Cook 1987).
//!
//! The key light is treated as directional. The scene is rasterized once along the light
//! direction `l` into an orthographic depth map storing, per texel, the largest `l·p` (the
//! surface nearest the light). A point `p` with normal `n` is lit when
//! `l·p' + bias >= map(p')`, where `p' = p + n·texel` is pushed off its surface (normal-offset)
//! and the bias grows with the slope `tan θ = sin θ / cos θ`, `cos θ = n·l`. Averaging that test
//! over a 4x4 block of texels gives soft shadow edges (the four corner taps are tried first, and
//! when they agree the other twelve are skipped).
//!
//! The same map gives the floor's contact shadow: background samples whose view ray meets the
//! ground plane below the scene are darkened where that ground point is in shadow.

use super::camera::View;
use super::math::{add, cross, dot, normalize_or, scale};
use super::prep::PreparedMesh;
use super::raster::{raster_segment, raster_triangle, Frame};

/// An orthographic depth map seen from the key light.
pub(crate) struct ShadowMap {
    size: usize,
    depth: Vec<f32>,
    ax: [f32; 3],
    ay: [f32; 3],
    dir: [f32; 3],
    x0: f32,
    y0: f32,
    d0: f32,
    texel: f32,
}

/// Texels per side of the map.
const SIZE: usize = 512;
/// PCF sample spacing, in texels.
const PCF_STEP: f32 = 1.0;

impl ShadowMap {
    /// Builds the map for light direction `toward_light` (unit) over the box `min..max`, from
    /// the meshes and the polylines (drawn as thin lines).
    pub fn build(toward_light: [f32; 3], min: [f32; 3], max: [f32; 3], meshes: &[PreparedMesh<'_>], lines: &[&[[f32; 3]]]) -> ShadowMap {
        let dir = toward_light;
        let helper = if dir[1].abs() < 0.9 { [0.0, 1.0, 0.0] } else { [1.0, 0.0, 0.0] };
        let ax = normalize_or(cross(helper, dir), [1.0, 0.0, 0.0]);
        let ay = cross(dir, ax);
        let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
        for k in 0..8 {
            let c = [
                if k & 1 == 0 { min[0] } else { max[0] },
                if k & 2 == 0 { min[1] } else { max[1] },
                if k & 4 == 0 { min[2] } else { max[2] },
            ];
            for (j, axis) in [ax, ay, dir].iter().enumerate() {
                lo[j] = lo[j].min(dot(c, *axis));
                hi[j] = hi[j].max(dot(c, *axis));
            }
        }
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-6);
        let texel = extent / (SIZE - 8) as f32;
        let mut map = ShadowMap {
            size: SIZE,
            depth: vec![0.0; SIZE * SIZE],
            ax,
            ay,
            dir,
            x0: lo[0] - 4.0 * texel,
            y0: lo[1] - 4.0 * texel,
            // Depths are shifted to start at 1 so they stay above the empty value 0.
            d0: lo[2] - 1.0,
            texel,
        };
        for mesh in meshes {
            for t in &mesh.triangles {
                let s = t.map(|i| map.to_map(mesh.positions[i as usize]));
                raster_triangle(SIZE, SIZE, &mut map.depth, s, |_, _| {});
            }
        }
        for points in lines {
            for pair in points.windows(2) {
                let (a, b) = (map.to_map(pair[0]), map.to_map(pair[1]));
                raster_segment(SIZE, SIZE, &mut map.depth, a, b, 0.75, |_, _| {});
            }
        }
        map
    }

    /// World point to map coordinates `(texel x, texel y, shifted depth)`.
    #[inline]
    fn to_map(&self, p: [f32; 3]) -> [f32; 3] {
        [
            (dot(p, self.ax) - self.x0) / self.texel,
            (dot(p, self.ay) - self.y0) / self.texel,
            dot(p, self.dir) - self.d0,
        ]
    }

    /// Fraction of the key light reaching `p` (unit normal `n`), from 0 (shadow) to 1 (lit).
    pub fn visibility(&self, p: [f32; 3], n: [f32; 3]) -> f32 {
        let cos = dot(n, self.dir);
        if cos <= 0.0 {
            return 1.0; // facing away: the lighting term is zero anyway
        }
        let offset = self.texel * 1.5;
        let q = [p[0] + n[0] * offset, p[1] + n[1] * offset, p[2] + n[2] * offset];
        let m = self.to_map(q);
        let tan = (1.0 - cos * cos).max(0.0).sqrt() / cos.max(0.05);
        let bias = self.texel * (1.0 + tan.min(8.0));
        let lit_at = |i: usize, j: usize| {
            let sx = m[0] + (i as f32 - 1.5) * PCF_STEP;
            let sy = m[1] + (j as f32 - 1.5) * PCF_STEP;
            if !(sx >= 0.0 && sy >= 0.0) {
                return 1.0;
            }
            let (x, y) = (sx as usize, sy as usize);
            if x >= self.size || y >= self.size || m[2] + bias >= self.depth[y * self.size + x] {
                1.0
            } else {
                0.0
            }
        };
        // The four corner taps first: when they agree the block is taken as wholly lit or
        // wholly shadowed (the penumbra is narrower than the block), which skips 12 taps on
        // almost every sample.
        let corners = lit_at(0, 0) + lit_at(3, 0) + lit_at(0, 3) + lit_at(3, 3);
        if corners == 0.0 || corners == 4.0 {
            return corners / 4.0;
        }
        let mut lit = 0.0;
        for j in 0..4 {
            for i in 0..4 {
                lit += lit_at(i, j);
            }
        }
        lit / 16.0
    }
}

/// How much a fully shadowed floor point darkens the background.
const GROUND_SHADOW_STRENGTH: f32 = 0.45;

/// Darkens the background samples (depth still 0) of `frame` whose view ray meets the plane
/// `up·p = height` (in front of the camera) at a point the key light does not reach.
pub(crate) fn darken_ground(frame: &mut Frame, view: &View, map: &ShadowMap, up: [f32; 3], height: f32) {
    let eye_height = dot(view.eye, up);
    for y in 0..frame.height {
        for x in 0..frame.width {
            let i = y * frame.width + x;
            if frame.depth[i] != 0.0 {
                continue;
            }
            let sx = (x as f32 + 0.5 - view.cx) / view.focal;
            let sy = (view.cy - y as f32 - 0.5) / view.focal;
            let dir = add(view.forward, add(scale(view.right, sx), scale(view.up, sy)));
            let rate = dot(dir, up);
            if rate >= 0.0 {
                continue; // the ray never comes down to the floor
            }
            let t = (height - eye_height) / rate;
            if !(t > 0.0 && t.is_finite()) {
                continue;
            }
            let ground = add(view.eye, scale(dir, t));
            let vis = map.visibility(ground, up);
            if vis < 1.0 {
                let k = 1.0 - GROUND_SHADOW_STRENGTH * (1.0 - vis);
                frame.color[i] = scale(frame.color[i], k);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{prep::prepare, shapes, MeshItem};

    #[test]
    fn a_box_shadows_the_floor_below_it_but_not_beside_it() {
        let (p, t) = shapes::box_mesh([0.0, 1.0, 0.0], [0.5, 0.5, 0.5]);
        let mesh = MeshItem {
            positions: p,
            triangles: t,
            color: [200; 3],
        };
        let prepared = [prepare(&mesh, 0).unwrap()];
        let up = [0.0, 1.0, 0.0];
        let map = ShadowMap::build(up, [-3.0, 0.0, -3.0], [3.0, 1.5, 3.0], &prepared, &[]);
        assert!(map.visibility([0.0, 0.0, 0.0], up) < 0.01);
        assert!(map.visibility([2.0, 0.0, 0.0], up) > 0.99);
        // The lit top of the box does not shadow itself.
        assert!(map.visibility([0.0, 1.5, 0.0], up) > 0.99);
    }
}
