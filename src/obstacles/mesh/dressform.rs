//! Procedural dress forms ("mannequins"): the obstacles of the paper's table
//! (Landovskaya, Landovsky & Frolovsky used female dress forms of 4800 and 8350 faces).
//!
//! The form is a body of revolution with an elliptical cross-section: at height `y` the
//! section is `(a(y) cos th, y, b(y) sin th)`, the half-widths `a` (side to side) and `b`
//! (front to back) interpolated with smoothstep between key sections: hip cut, hips, waist,
//! bust, under-arm, shoulders, neck base, neck stub (heights in metres, `y` up, total
//! [`HEIGHT`]). `R` rings of `S` vertices at equal heights, joined by quads split in two, plus
//! a fan cap at the bottom and at the top, give a watertight surface of exactly `2 S R` faces
//! with outward (counter-clockwise seen from outside) winding.
//!
//! [`dress_form`] picks `S` and `R` near `sqrt(target / 2)` so that `2 S R` is as close to the
//! target as possible: [`PRESET_4800`] gives exactly 4800 faces (`S = 48, R = 50`) and
//! [`PRESET_8350`] gives 8352 (`S = 58, R = 72`).

use crate::obstacles::mesh::TriMesh;
use crate::{Result, WeftError};

/// Face-count target of the paper's first dress form.
pub const PRESET_4800: usize = 4800;
/// Face-count target of the paper's second dress form (yields 8352 faces).
pub const PRESET_8350: usize = 8350;
/// Height of the form (metres).
pub const HEIGHT: f32 = 0.80;

/// Key sections `(height, half-width a, half-depth b)` in metres.
const KEYS: [(f32, f32, f32); 12] = [
    (0.00, 0.160, 0.115),
    (0.10, 0.180, 0.130),
    (0.20, 0.170, 0.120),
    (0.30, 0.135, 0.100),
    (0.42, 0.160, 0.120),
    (0.48, 0.170, 0.135),
    (0.56, 0.165, 0.115),
    (0.63, 0.190, 0.105),
    (0.68, 0.150, 0.090),
    (0.71, 0.070, 0.060),
    (0.74, 0.055, 0.052),
    (0.80, 0.052, 0.050),
];

/// Half-widths `(a, b)` of the section at height `y` (clamped to the form).
pub fn section(y: f32) -> (f32, f32) {
    let y = y.clamp(0.0, HEIGHT);
    let i = KEYS.iter().rposition(|k| k.0 <= y).unwrap_or(0).min(KEYS.len() - 2);
    let (k0, k1) = (KEYS[i], KEYS[i + 1]);
    let t = ((y - k0.0) / (k1.0 - k0.0)).clamp(0.0, 1.0);
    let s = t * t * (3.0 - 2.0 * t);
    (k0.1 + s * (k1.1 - k0.1), k0.2 + s * (k1.2 - k0.2))
}

/// Segments around and rings up chosen for a face-count target (module doc).
pub fn dims_for(target_faces: usize) -> Result<(usize, usize)> {
    if !(16..=4_000_000).contains(&target_faces) {
        return Err(WeftError::param("dress form faces", target_faces, "must be between 16 and 4000000"));
    }
    let half = target_faces as f64 / 2.0;
    let r0 = half.sqrt();
    let mut best = (usize::MAX, usize::MAX, 0, 0);
    let lo = ((0.7 * r0).floor() as usize).max(4);
    let hi = (1.4 * r0).ceil() as usize;
    for s in lo..=hi {
        let r = ((half / s as f64).round() as usize).max(2);
        let key = ((2 * s * r).abs_diff(target_faces), s.abs_diff(r), s, r);
        if (key.0, key.1, key.2) < (best.0, best.1, best.2) {
            best = key;
        }
    }
    Ok((best.2, best.3))
}

/// A closed dress form of `segments` around and `rings` up (`2 * segments * rings` faces).
pub fn dress_form_with(segments: usize, rings: usize) -> Result<TriMesh> {
    if segments < 3 || rings < 2 || segments.saturating_mul(rings) > 2_000_000 {
        return Err(WeftError::param(
            "dress form resolution",
            format!("{segments} x {rings}"),
            "needs at least 3 segments, 2 rings and at most 2000000 vertices",
        ));
    }
    let (s, r) = (segments, rings);
    let mut v = Vec::with_capacity(s * r + 2);
    for i in 0..r {
        let y = HEIGHT * i as f32 / (r - 1) as f32;
        let (a, b) = section(y);
        for j in 0..s {
            let th = std::f32::consts::TAU * j as f32 / s as f32;
            v.push([a * th.cos(), y, b * th.sin()]);
        }
    }
    let (bottom, top) = ((s * r) as u32, (s * r + 1) as u32);
    v.push([0.0, 0.0, 0.0]);
    v.push([0.0, HEIGHT, 0.0]);
    let id = |i: usize, j: usize| (i * s + j % s) as u32;
    let mut f = Vec::with_capacity(2 * s * r);
    for i in 0..r - 1 {
        for j in 0..s {
            let (v00, v01, v10, v11) = (id(i, j), id(i, j + 1), id(i + 1, j), id(i + 1, j + 1));
            f.push([v00, v10, v01]);
            f.push([v01, v10, v11]);
        }
    }
    for j in 0..s {
        f.push([bottom, id(0, j), id(0, j + 1)]);
        f.push([top, id(r - 1, j + 1), id(r - 1, j)]);
    }
    let (mesh, report) = TriMesh::new(v, f)?;
    if !report.skipped_faces.is_empty() || report.boundary_edges > 0 || report.non_manifold_edges > 0 {
        return Err(WeftError::InvalidMesh {
            source_name: Some("dress form".into()),
            reason: format!("resolution {s} x {r} is too fine: {:?}", report.warnings),
        });
    }
    Ok(mesh)
}

/// A closed dress form with a face count close to `target_faces` (16 ..= 4000000).
pub fn dress_form(target_faces: usize) -> Result<TriMesh> {
    let (s, r) = dims_for(target_faces)?;
    dress_form_with(s, r)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn check_closed_outward(m: &TriMesh) {
        let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
        for f in m.faces() {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                // +1 for a->b, -1 for b->a: consistent winding cancels on every edge
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += if a < b { 1 } else { -1 } * 10 + 1;
            }
        }
        // each edge used twice (+1 +1 = 2) in opposite directions (+10 -10 = 0)
        assert!(edges.values().all(|&c| c == 2), "not closed / inconsistent winding");
        let vol = m.signed_volume();
        assert!(vol > 0.0, "inward normals, volume {vol}");
        // a body this size: somewhere between a thin and a fat cylinder
        assert!(vol > 0.01 && vol < 0.1, "volume {vol}");
    }

    #[test]
    fn presets_exact_counts_closed_outward() {
        assert_eq!(dims_for(PRESET_4800).unwrap(), (48, 50));
        assert_eq!(dims_for(PRESET_8350).unwrap(), (58, 72));
        let a = dress_form(PRESET_4800).unwrap();
        assert_eq!(a.face_count(), 4800);
        check_closed_outward(&a);
        let b = dress_form(PRESET_8350).unwrap();
        assert_eq!(b.face_count(), 8352);
        check_closed_outward(&b);
        let (lo, hi) = b.bounds();
        assert_eq!((lo[1], hi[1]), (0.0, HEIGHT));
        assert!(hi[1] - lo[1] > hi[0] - lo[0] && hi[0] - lo[0] > hi[2] - lo[2]);
    }

    #[test]
    fn targets_near_and_bad_targets_rejected() {
        for t in [16, 100, 777, 3000, 20000] {
            let m = dress_form(t).unwrap();
            let got = m.face_count() as f64;
            assert!((got - t as f64).abs() <= 0.05 * t as f64 + 8.0, "{t} -> {got}");
            check_closed_outward(&m);
        }
        assert!(dress_form(3).is_err());
        assert!(dress_form(usize::MAX).is_err());
        assert!(dress_form_with(2, 5).is_err());
    }

    #[test]
    fn waist_narrower_than_hips_and_bust() {
        let (hips, waist, bust) = (section(0.10).0, section(0.30).0, section(0.48).0);
        assert!(waist < hips && waist < bust);
        assert!(section(0.78).0 < 0.06);
    }
}
