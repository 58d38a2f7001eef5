//! Response to a mesh contact (Landovskaya, Landovsky & Frolovsky): put the particle back on its side at the
//! fabric thickness, and correct its velocity.
//!
//! **Position.** The paper returns the particle "along its trajectory" until it stands the
//! thickness `Th` off the face. With `hx = m.(x - c)` and `hp = m.(p - c)` the heights of the
//! start and the prediction above the contact plane (`m` the contact normal, `c` its point),
//! the point of the path at height `Th` is `x + tau (p - x)` with
//! `tau = (hx - Th) / (hx - hp)`. That needs the particle to approach the face (`hx > hp`) and
//! to have started at least `Th` away (`hx >= Th`). Otherwise there is no such point on the
//! path: a particle that started inside the layer and crossed the plane (`hx > 0 > hp`) stays
//! where it started, which lies before the crossing (pushing its `p`, which can lie deep
//! behind the plane and far along the path, along the normal can leave a fast particle in a
//! concave region inside a neighbouring face, `tests/obstacles.rs`); one that rested inside the layer or slid along it without crossing
//! is pushed along the normal by `Th - hp`, keeping its sliding.
//!
//! **Bound at concave creases.** Contacts are found once a substep; the solver's sweeps then
//! project onto the planes found. A particle that the constraints drag along the form across
//! a concave crease (e.g. neck to shoulder) can end that substep inside the neighbouring face,
//! by up to ~0.15 mm in the worst case found (a drag of ~80 m/s); the next substep's contact
//! puts it out. `tests/obstacles.rs` holds the dress form to 0.3 mm. Finding the contacts
//! again after the sweeps would remove it at the cost of a second narrowphase a substep.
//!
//! **Velocity.** Inelastic contact with Coulomb friction: if the velocity points into the face
//! (`v_n = v.m < 0`) the normal part is removed and the tangential part
//! `v_t = v - v_n m` shrinks by `mu |v_n|`: `v' = v_t max(0, 1 - mu |v_n| / |v_t|)`
//! (static friction when `|v_t| <= mu |v_n|`). A velocity leaving the face is unchanged.

use crate::model::shapes::{dot, sub};
use crate::obstacles::mesh::narrow::Contact;

/// The corrected position of a particle whose step `x -> p` made contact `c` (module doc).
pub fn resolve_position(x: [f32; 3], p: [f32; 3], c: &Contact, th: f32) -> [f32; 3] {
    resolve_against_plane(x, p, c.point, c.normal, th, true)
}

/// The response of one contact plane (point `point`, unit normal `m`, stand-off `th`) to the
/// step `x -> p` (module doc). `stay`: a path that crossed the plane from inside the layer
/// goes back to `x` (a mesh, where a push along one face's normal can enter the mesh through
/// a neighbouring face); otherwise it is pushed (a convex shape, which the push cannot
/// enter). [`resolve_position`] and the obstacle stage's kernels share it.
#[inline]
pub(crate) fn resolve_against_plane(x: [f32; 3], p: [f32; 3], point: [f32; 3], m: [f32; 3], th: f32, stay: bool) -> [f32; 3] {
    let hx = dot(m, sub(x, point));
    let hp = dot(m, sub(p, point));
    if hx > hp && hx >= th {
        let tau = ((hx - th) / (hx - hp)).clamp(0.0, 1.0);
        [0, 1, 2].map(|k| x[k] + tau * (p[k] - x[k]))
    } else if stay && hx > 0.0 && hp < 0.0 {
        // Crossed the plane from inside the layer: stay at the start, which lies before the
        // crossing (the push below could carry a deep `p` through a neighbouring face).
        x
    } else if hp < th {
        let push = th - hp;
        [0, 1, 2].map(|k| p[k] + push * m[k])
    } else {
        p
    }
}

/// The velocity after an inelastic contact with Coulomb friction `mu` against unit normal
/// `normal` (module doc). Negative or NaN `mu` acts as 0.
pub fn resolve_velocity(v: [f32; 3], normal: [f32; 3], mu: f32) -> [f32; 3] {
    let vn = dot(v, normal);
    if vn >= 0.0 || vn.is_nan() {
        return v;
    }
    let vt = [0, 1, 2].map(|k| v[k] - vn * normal[k]);
    let lt = dot(vt, vt).sqrt();
    let drop = mu.max(0.0) * -vn;
    if lt <= drop {
        return [0.0; 3];
    }
    let keep = 1.0 - drop / lt;
    vt.map(|c| c * keep)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::obstacles::mesh::broadphase::BruteForce;
    use crate::obstacles::mesh::narrow::mesh_contact;

    use crate::obstacles::mesh::unit_square as square;

    #[test]
    fn back_along_the_path_to_thickness() {
        let m = square();
        let bp = BruteForce::new(&m);
        let (x, p, th) = ([0.2, 0.2, 1.0], [0.6, 0.2, -1.0], 0.1);
        let c = mesh_contact(&m, &bp, x, p, th).unwrap();
        let q = resolve_position(x, p, &c, th);
        assert!((q[2] - th).abs() < 1e-6, "{q:?}");
        assert!((q[0] - (0.2 + 0.4 * 0.45)).abs() < 1e-6, "{q:?}");
        // resting inside the layer and sliding: pushed along the normal
        let (x, p) = ([0.2, 0.2, 0.05], [0.3, 0.2, 0.04]);
        let c = mesh_contact(&m, &bp, x, p, th).unwrap();
        let q = resolve_position(x, p, &c, th);
        assert_eq!(q, [0.3, 0.2, 0.1]);
        // starting inside the layer and crossing the face: back to the start
        let (x, p) = ([0.2, 0.2, 0.05], [0.6, 0.2, -0.3]);
        let c = mesh_contact(&m, &bp, x, p, th).unwrap();
        assert_eq!(resolve_position(x, p, &c, th), x);
    }

    #[test]
    fn velocity_inelastic_with_friction() {
        let n = [0.0, 0.0, 1.0];
        assert_eq!(resolve_velocity([3.0, 0.0, -1.0], n, 0.0), [3.0, 0.0, 0.0]);
        assert_eq!(resolve_velocity([3.0, 0.0, -1.0], n, 0.5), [2.5, 0.0, 0.0]);
        assert_eq!(resolve_velocity([0.4, 0.0, -1.0], n, 0.5), [0.0; 3]);
        assert_eq!(resolve_velocity([3.0, 0.0, 1.0], n, 0.5), [3.0, 0.0, 1.0]);
        assert_eq!(resolve_velocity([3.0, 0.0, -1.0], n, f32::NAN), [3.0, 0.0, 0.0]);
    }
}
