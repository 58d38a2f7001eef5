//! The contact geometry of the analytic shapes (the method is in [`super`]): closest points,
//! the ball test shared by the sphere and the capsule, and the oriented box with its slab test.

use super::{add_scaled, dot, sub};

#[inline]
pub(super) fn sq(v: f32) -> f32 {
    v * v
}
#[inline]
pub(super) fn dist2(a: [f32; 3], b: [f32; 3]) -> f32 {
    let d = sub(a, b);
    dot(d, d)
}

/// Closest point of segment `a b` to `q`.
pub(super) fn closest_on_segment(q: [f32; 3], a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    let ab = sub(b, a);
    let l2 = dot(ab, ab);
    let t = if l2 > 0.0 { (dot(sub(q, a), ab) / l2).clamp(0.0, 1.0) } else { 0.0 };
    add_scaled(a, t, ab)
}

/// The point of the capsule axis `a b` closest to the path `x p` (segment-segment closest
/// points, Ericson 5.1.9, clamped; degenerate segments fall back to point queries).
pub(super) fn closest_axis_point_to_path(a: [f32; 3], b: [f32; 3], x: [f32; 3], p: [f32; 3]) -> [f32; 3] {
    let (d1, d2, r) = (sub(b, a), sub(p, x), sub(a, x));
    let (aa, ee, f) = (dot(d1, d1), dot(d2, d2), dot(d2, r));
    if aa <= 0.0 {
        return a;
    }
    if ee <= 0.0 {
        return closest_on_segment(x, a, b);
    }
    let c = dot(d1, r);
    let bb = dot(d1, d2);
    let den = aa * ee - bb * bb;
    let mut s = if den > 0.0 {
        ((bb * f - c * ee) / den).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let t = (bb * s + f) / ee;
    if t < 0.0 {
        s = (-c / aa).clamp(0.0, 1.0);
    } else if t > 1.0 {
        s = ((bb - c) / aa).clamp(0.0, 1.0);
    }
    add_scaled(a, s, d1)
}

/// Sphere (or capsule slice) contact: surface point and outward normal.
pub(super) fn ball_contact(c: [f32; 3], r: f32, x: [f32; 3], p: [f32; 3], th: f32, reach: f32) -> Option<([f32; 3], [f32; 3])> {
    let dp = sub(p, c);
    let l2 = dot(dp, dp);
    if l2 < sq(r + reach) {
        let l = l2.sqrt();
        let n = if l > 0.0 {
            dp.map(|k| k / l)
        } else {
            let dx = sub(x, c);
            let lx = dot(dx, dx).sqrt();
            if lx > 0.0 {
                dx.map(|k| k / lx)
            } else {
                [0.0, 1.0, 0.0]
            }
        };
        return Some((add_scaled(c, r, n), n));
    }
    // Crossing: first entry into the ball of radius r + th.
    let d = sub(p, x);
    let f = sub(x, c);
    let a = dot(d, d);
    let b = dot(f, d);
    let cc = dot(f, f) - sq(r + th);
    if a <= 0.0 || cc <= 0.0 || b >= 0.0 {
        return None;
    }
    let disc = b * b - a * cc;
    if disc < 0.0 {
        return None;
    }
    let t = (-b - disc.sqrt()) / a;
    if !(0.0..=1.0).contains(&t) {
        return None;
    }
    let e = sub(add_scaled(x, t, d), c);
    let l = dot(e, e).sqrt();
    let n = if l > 0.0 { e.map(|k| k / l) } else { [0.0, 1.0, 0.0] };
    Some((add_scaled(c, r, n), n))
}

pub(super) fn to_local(axes: &[[f32; 3]; 3], v: [f32; 3]) -> [f32; 3] {
    [dot(axes[0], v), dot(axes[1], v), dot(axes[2], v)]
}
pub(super) fn to_world(axes: &[[f32; 3]; 3], l: [f32; 3]) -> [f32; 3] {
    [0, 1, 2].map(|k| axes[0][k] * l[0] + axes[1][k] * l[1] + axes[2][k] * l[2])
}

/// Slab test of segment `x p` (local) against the box `|l| <= g`: entry time and axis.
pub(super) fn slab_entry(x: [f32; 3], p: [f32; 3], g: [f32; 3]) -> Option<(f32, usize)> {
    let (mut t0, mut t1, mut axis) = (0.0f32, 1.0f32, usize::MAX);
    for k in 0..3 {
        let d = p[k] - x[k];
        if d == 0.0 {
            if x[k].abs() > g[k] {
                return None;
            }
            continue;
        }
        let (mut a, mut b) = ((-g[k] - x[k]) / d, (g[k] - x[k]) / d);
        if a > b {
            std::mem::swap(&mut a, &mut b);
        }
        if a > t0 {
            t0 = a;
            axis = k;
        }
        t1 = t1.min(b);
        if t0 > t1 {
            return None;
        }
    }
    (axis != usize::MAX).then_some((t0, axis))
}

pub(super) fn box_contact(
    center: [f32; 3],
    half: [f32; 3],
    axes: &[[f32; 3]; 3],
    x: [f32; 3],
    p: [f32; 3],
    th: f32,
    reach: f32,
) -> Option<([f32; 3], [f32; 3])> {
    let lp = to_local(axes, sub(p, center));
    let lx = to_local(axes, sub(x, center));
    let clamped = [0, 1, 2].map(|k| lp[k].clamp(-half[k], half[k]));
    let out = sub(lp, clamped);
    let o2 = dot(out, out);
    let face = |k: usize, sign: f32, l: [f32; 3]| {
        let mut q = [0, 1, 2].map(|j| l[j].clamp(-half[j], half[j]));
        q[k] = sign * half[k];
        let mut n = [0.0; 3];
        n[k] = sign;
        (add_scaled(center, 1.0, to_world(axes, q)), to_world(axes, n))
    };
    if o2 > 0.0 {
        if o2 < sq(reach) {
            let l = o2.sqrt();
            return Some((add_scaled(center, 1.0, to_world(axes, clamped)), to_world(axes, out.map(|k| k / l))));
        }
    } else {
        // p inside: the face the step entered through, else the face of least penetration.
        let x_out = (0..3).any(|k| lx[k].abs() > half[k]);
        if x_out {
            if let Some((_, k)) = slab_entry(lx, lp, half) {
                let sign = if lx[k] > lp[k] { 1.0 } else { -1.0 };
                return Some(face(k, sign, lp));
            }
        }
        let k = (0..3).fold(0, |b, k| if half[k] - lp[k].abs() < half[b] - lp[b].abs() { k } else { b });
        return Some(face(k, if lp[k] >= 0.0 { 1.0 } else { -1.0 }, lp));
    }
    // Crossing: the step passed through the box grown by th.
    let grown = half.map(|h| h + th);
    if (0..3).all(|k| lx[k].abs() <= grown[k]) {
        return None;
    }
    let (t, k) = slab_entry(lx, lp, grown)?;
    let sign = if lx[k] > lp[k] { 1.0 } else { -1.0 };
    let entry = add_scaled(lx, t, sub(lp, lx));
    Some(face(k, sign, entry))
}
