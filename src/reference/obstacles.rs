//! Analytic obstacles in f64 for the reference step: plane, sphere, capsule and box, static or
//! moving with a constant velocity (Landovskaya, Landovsky & Frolovsky; the world's version is
//! `src/model/shapes.rs`, `src/obstacles/`).
//!
//! This is a second, deliberately naive reading of the same response, written from the method
//! rather than from the kernels. Every shape is reduced to one query, [`Solid::closest`]: the
//! closest surface point `c` of a point `q`, the outward unit normal `n` there, and the signed
//! distance `s = n.(q - c)` (negative inside). Per substep of length `h` ending at time `t`:
//!
//! 1. **Contact** of the path `x - u h -> p` (the start taken in the obstacle's frame at `t`,
//!    `u` its velocity): if `s(p) < reach` (`reach = Th + max(Th, 3 mm)`, inside included) the
//!    contact plane is `closest(p)`; otherwise, if the path starts outside the shape grown by
//!    the thickness `Th`, it is sampled at 16 points and the first sample inside the grown shape
//!    is bisected (40 halvings) to the entry point, whose tangent plane is the contact (the
//!    continuous test against tunnelling; a generic search instead of the world's closed-form
//!    roots and slab test). The approach speed `a = max(0, -n.(v - u))` of the predicted
//!    velocity is kept with it.
//! 2. **Response along the path**: with `h_x = n.(x - u h - c)`, `h_p = n.(p - c)`, if
//!    `h_x > h_p` and `h_x >= Th` the particle goes back along its path to the point standing
//!    `Th` off the plane, `p = x' + τ (p - x')`, `τ = (h_x - Th)/(h_x - h_p)` clamped to
//!    `[0, 1]`; else if `h_p < Th` it is pushed along the normal by `Th - h_p`.
//! 3. **Projection** after each constraint sweep: `p += max(0, Th - n.(p - c)) n` (the contact
//!    planes as inequality constraints, Müller et al. 2007).
//! 4. **Velocity** after the update, for a particle within `Th + 0.1 mm` of its plane: relative
//!    to the obstacle, `w = v - u` loses its approaching normal part and Coulomb friction shrinks
//!    its tangential part by `μ max(a, -n.w)` (to zero if that is more than it has).
//!
//! A box holding `p` inside gives the face its step entered through when the step started
//! outside (found the same way, by bisection to the surface), else the face of least
//! penetration. Crossings are found by sampling, so a path that enters and leaves the grown
//! shape between two samples (a step longer than 1/16 of the shape's size) is missed; with the
//! reference's small substeps even a crossing needs a step longer than 3 mm.

use crate::model::description::ObstacleDesc;
use crate::model::shapes::Shape;
use crate::model::shapes::MIN_MARGIN;

/// A particle this far beyond the thickness still counts as touching (the world's value).
const TOUCH_SLACK: f64 = 1e-4;
/// Samples of a path in the crossing test.
const PATH_SAMPLES: usize = 16;

type V3 = [f64; 3];

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn len(a: V3) -> f64 {
    dot(a, a).sqrt()
}
fn lerp(a: V3, b: V3, t: f64) -> V3 {
    add(a, scale(sub(b, a), t))
}
fn f64s(a: [f32; 3]) -> V3 {
    a.map(f64::from)
}

/// An analytic shape in f64, at time 0.
#[derive(Clone, Debug)]
enum Solid {
    Plane { point: V3, normal: V3 },
    Sphere { center: V3, radius: f64 },
    Capsule { a: V3, b: V3, radius: f64 },
    Box { center: V3, half: V3, axes: [V3; 3] },
}

impl Solid {
    fn from_shape(s: &Shape) -> Solid {
        match s {
            Shape::Plane { point, normal } => {
                let n = f64s(*normal);
                Solid::Plane {
                    point: f64s(*point),
                    normal: scale(n, 1.0 / len(n)),
                }
            }
            Shape::Sphere { center, radius } => Solid::Sphere {
                center: f64s(*center),
                radius: *radius as f64,
            },
            Shape::Capsule { a, b, radius } => Solid::Capsule {
                a: f64s(*a),
                b: f64s(*b),
                radius: *radius as f64,
            },
            Shape::Box { center, half, axes } => Solid::Box {
                center: f64s(*center),
                half: f64s(*half),
                axes: axes.map(f64s),
            },
        }
    }

    /// Closest surface point of `q` (the shape moved by `shift`), outward normal, signed
    /// distance.
    fn closest(&self, q: V3, shift: V3) -> (V3, V3, f64) {
        let ball = |c: V3, r: f64| {
            let d = sub(q, c);
            let l = len(d);
            let n = if l > 0.0 { scale(d, 1.0 / l) } else { [0.0, 1.0, 0.0] };
            (add(c, scale(n, r)), n, l - r)
        };
        match self {
            Solid::Plane { point, normal } => {
                let s = dot(*normal, sub(q, add(*point, shift)));
                (sub(q, scale(*normal, s)), *normal, s)
            }
            Solid::Sphere { center, radius } => ball(add(*center, shift), *radius),
            Solid::Capsule { a, b, radius } => {
                let (a, b) = (add(*a, shift), add(*b, shift));
                let ab = sub(b, a);
                let l2 = dot(ab, ab);
                let t = if l2 > 0.0 { (dot(sub(q, a), ab) / l2).clamp(0.0, 1.0) } else { 0.0 };
                ball(lerp(a, b, t), *radius)
            }
            Solid::Box { center, half, axes } => {
                let c = add(*center, shift);
                let l = axes.map(|ax| dot(ax, sub(q, c)));
                let world = |m: V3| add(c, add(add(scale(axes[0], m[0]), scale(axes[1], m[1])), scale(axes[2], m[2])));
                if (0..3).any(|k| l[k].abs() > half[k]) {
                    let cl: V3 = std::array::from_fn(|k| l[k].clamp(-half[k], half[k]));
                    let point = world(cl);
                    let d = sub(q, point);
                    let s = len(d);
                    (point, scale(d, 1.0 / s), s)
                } else {
                    let k = (0..3).fold(0, |b, k| if half[k] - l[k].abs() < half[b] - l[b].abs() { k } else { b });
                    let sign = if l[k] >= 0.0 { 1.0 } else { -1.0 };
                    let mut m = l;
                    m[k] = sign * half[k];
                    (world(m), scale(axes[k], sign), l[k].abs() - half[k])
                }
            }
        }
    }
}

/// One obstacle of the reference: shape, velocity, friction coefficient.
#[derive(Clone, Debug)]
pub(super) struct Obstacle64 {
    solid: Solid,
    velocity: V3,
    friction: f64,
}

/// A contact plane: point, unit normal (zero: none) and approach speed.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Contact {
    point: V3,
    normal: V3,
    approach: f64,
}

impl Obstacle64 {
    /// The f64 copy of `o` (`None` for a mesh), with `default_friction` unless it has its own.
    pub(super) fn from_desc(o: &ObstacleDesc, default_friction: f32) -> Option<Obstacle64> {
        o.shape.as_ref().map(|s| Obstacle64 {
            solid: Solid::from_shape(s),
            velocity: f64s(o.velocity),
            friction: o.friction.unwrap_or(default_friction) as f64,
        })
    }

    /// Signed distance of `q` to the surface at time `t` (negative inside).
    pub(super) fn signed_distance(&self, q: V3, t: f64) -> f64 {
        self.solid.closest(q, scale(self.velocity, t)).2
    }

    /// The contact of the path `x -> p` over a substep of length `h` ending at `t` (stage 1),
    /// for a particle of thickness `th` and predicted velocity `v`.
    pub(super) fn contact(&self, x: V3, p: V3, v: V3, th: f64, t: f64, h: f64) -> Contact {
        let shift = scale(self.velocity, t);
        let xs = sub(x, scale(self.velocity, h));
        let reach = th + th.max(MIN_MARGIN as f64);
        let (c, n, s) = self.solid.closest(p, shift);
        let sx = self.solid.closest(xs, shift).2;
        // The first point of the path closer than `level` to the surface, if any.
        let entry = |level: f64| {
            let inside = |k: f64| self.solid.closest(lerp(xs, p, k), shift).2 < level;
            (1..=PATH_SAMPLES)
                .map(|k| k as f64 / PATH_SAMPLES as f64)
                .find(|&k| inside(k))
                .map(|hi| {
                    let (mut lo, mut hi) = (hi - 1.0 / PATH_SAMPLES as f64, hi);
                    for _ in 0..40 {
                        let mid = 0.5 * (lo + hi);
                        if inside(mid) {
                            hi = mid;
                        } else {
                            lo = mid;
                        }
                    }
                    let (c, n, _) = self.solid.closest(lerp(xs, p, hi), shift);
                    (c, n)
                })
        };
        let plane = if s < 0.0 && sx > 0.0 && matches!(self.solid, Solid::Box { .. }) {
            // Inside a box from outside: the face the step entered through.
            entry(0.0).or(Some((c, n)))
        } else if s < reach {
            Some((c, n))
        } else if sx >= th {
            entry(th)
        } else {
            None
        };
        match plane {
            Some((point, normal)) => Contact {
                point,
                normal,
                approach: (-dot(normal, sub(v, self.velocity))).max(0.0),
            },
            None => Contact::default(),
        }
    }

    /// Moves `p` back along its path out of contact `c` (stage 2).
    pub(super) fn resolve(&self, c: &Contact, x: V3, p: &mut V3, th: f64, h: f64) {
        if c.normal == [0.0; 3] {
            return;
        }
        let xs = sub(x, scale(self.velocity, h));
        let (hx, hp) = (dot(c.normal, sub(xs, c.point)), dot(c.normal, sub(*p, c.point)));
        if hx > hp && hx >= th {
            *p = lerp(xs, *p, ((hx - th) / (hx - hp)).clamp(0.0, 1.0));
        } else if hp < th {
            *p = add(*p, scale(c.normal, th - hp));
        }
    }

    /// Projects `p` out of contact `c` (stage 3).
    pub(super) fn project(c: &Contact, p: &mut V3, th: f64) {
        let d = th - dot(c.normal, sub(*p, c.point));
        if d > 0.0 {
            *p = add(*p, scale(c.normal, d));
        }
    }

    /// Inelastic contact with Coulomb friction for a particle at `x` with velocity `v` (stage 4).
    pub(super) fn velocity(&self, c: &Contact, x: V3, v: &mut V3, th: f64) {
        if c.normal == [0.0; 3] || dot(c.normal, sub(x, c.point)) > th + TOUCH_SLACK {
            return;
        }
        let w = sub(*v, self.velocity);
        let wn = dot(w, c.normal);
        let wt = sub(w, scale(c.normal, wn));
        let lt = len(wt);
        let drop = self.friction * (-wn).max(c.approach);
        let keep = if lt <= drop { 0.0 } else { 1.0 - drop / lt };
        *v = add(self.velocity, add(scale(wt, keep), scale(c.normal, wn.max(0.0))));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ob(s: Shape) -> Obstacle64 {
        Obstacle64::from_desc(
            &ObstacleDesc {
                shape: Some(s),
                velocity: [0.0; 3],
                friction: None,
            },
            0.0,
        )
        .unwrap()
    }

    #[test]
    fn closest_points_and_signed_distances_of_each_shape() {
        let s = ob(Shape::Sphere {
            center: [0.0, 1.0, 0.0],
            radius: 0.5,
        });
        assert!((s.signed_distance([0.0, 2.0, 0.0], 0.0) - 0.5).abs() < 1e-12);
        let c = ob(Shape::Capsule {
            a: [0.0; 3],
            b: [1.0, 0.0, 0.0],
            radius: 0.1,
        });
        assert!((c.signed_distance([0.5, 0.3, 0.0], 0.0) - 0.2).abs() < 1e-7);
        assert!((c.signed_distance([1.3, 0.0, 0.0], 0.0) - 0.2).abs() < 1e-7);
        let b = ob(Shape::Box {
            center: [0.0; 3],
            half: [1.0, 0.5, 0.25],
            axes: Shape::axes_from_euler_deg([0.0; 3]),
        });
        assert!(
            (b.signed_distance([0.0, 0.0, 0.1], 0.0) + 0.15).abs() < 1e-7,
            "inside: nearest face"
        );
        assert!((b.signed_distance([2.0, 0.0, 0.0], 0.0) - 1.0).abs() < 1e-7);
        let p = ob(Shape::plane([0.0; 3], [0.0, 2.0, 0.0]).unwrap());
        assert_eq!(p.signed_distance([3.0, -0.25, 1.0], 0.0), -0.25);
        // A moving obstacle is where its velocity took it.
        let m = Obstacle64 {
            velocity: [1.0, 0.0, 0.0],
            ..s
        };
        assert!((m.signed_distance([2.0, 1.0, 0.0], 1.5) - 0.0).abs() < 1e-12);
    }

    #[test]
    fn a_fast_path_through_a_sphere_is_caught_and_sent_back() {
        let s = ob(Shape::Sphere {
            center: [0.0; 3],
            radius: 0.5,
        });
        let (x, p, th) = ([0.0, 2.0, 0.0], [0.0, -2.0, 0.0], 0.01);
        let c = s.contact(x, p, [0.0, -240.0, 0.0], th, 0.0, 1.0 / 60.0);
        assert!((c.normal[1] - 1.0).abs() < 1e-9 && (c.point[1] - 0.5).abs() < 1e-9, "{c:?}");
        assert_eq!(c.approach, 240.0);
        let mut q = p;
        s.resolve(&c, x, &mut q, th, 1.0 / 60.0);
        assert!((q[1] - 0.51).abs() < 1e-9, "{q:?}");
        let mut v = [3.0, -240.0, 0.0];
        s.velocity(&c, q, &mut v, th);
        assert_eq!(v, [3.0, 0.0, 0.0], "no friction: the tangential part stays");
    }
}
