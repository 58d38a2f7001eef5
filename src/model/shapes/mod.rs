//! Analytic obstacles: plane (a solid half-space), sphere, capsule and box (oriented), each
//! tested against a particle's whole step `x -> p`.
//!
//! A contact is a *tangent plane*: a point on the obstacle's surface, the outward unit normal
//! there, and the depth `Th - n.(p - point)`, how far `p` must move along the normal to stand
//! the cloth thickness `Th` off the surface (Landovskaya, Landovsky & Frolovsky: "stand off the face by the
//! fabric thickness"). The solver keeps `n.(p - point) >= Th` as an inequality constraint
//! (`src/obstacles/`).
//!
//! Two tests, in this order (the same two as the mesh narrowphase, `narrow.rs`):
//!
//! 1. **Proximity.** If `p` is closer than `reach` (the thickness plus a margin) to the
//!    surface, or inside the solid, the contact is at the closest surface point (sphere:
//!    `c + r (p - c)/|p - c|`; capsule: the same about the closest axis point; box: the
//!    clamped point, or for an inside point the face of least penetration, or the face the
//!    step entered through when `x` started outside).
//! 2. **Crossing (continuous).** Otherwise `p` is clear, but a fast particle may have passed
//!    *through* the obstacle in one step. The segment is intersected with the obstacle grown
//!    by `Th` (sphere: the first root `t` of `|x + t (p - x) - c|^2 = (r + Th)^2`; capsule: the
//!    same about the axis point closest to the segment; box: the slab test, Kay & Kajiya) and,
//!    if it enters in `t in [0, 1]`, the contact is the tangent plane at the entry point. The
//!    response then puts `p` back on the side it came from: no tunnelling.
//!
//! A moving obstacle is tested in its own frame at the end of the step: the caller shifts the
//! start by the obstacle's displacement, `x - u h` (relative motion).

mod geometry;

use geometry::{ball_contact, box_contact, closest_axis_point_to_path, closest_on_segment, dist2, sq, to_local};

/// Smallest obstacle contact margin beyond the particle's thickness, m.
pub const MIN_MARGIN: f32 = 3e-3;

/// Cosine of the angle below which a plane normal is refused (`|n| = 1` is required).
const UNIT_TOL: f32 = 1e-3;

/// An analytic obstacle shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// The solid half-space `n.(q - point) <= 0`; `normal` is unit and points out of the solid.
    Plane {
        /// A point on the plane.
        point: [f32; 3],
        /// Outward unit normal.
        normal: [f32; 3],
    },
    /// A solid ball.
    Sphere {
        /// Centre.
        center: [f32; 3],
        /// Radius (> 0).
        radius: f32,
    },
    /// All points within `radius` of the segment `a b`.
    Capsule {
        /// One end of the axis.
        a: [f32; 3],
        /// The other end of the axis.
        b: [f32; 3],
        /// Radius (> 0).
        radius: f32,
    },
    /// A solid box: `center + axes * l` for `|l_k| <= half[k]`; `axes` are orthonormal
    /// (identity for an axis-aligned box).
    Box {
        /// Centre.
        center: [f32; 3],
        /// Half extents along the three axes (> 0).
        half: [f32; 3],
        /// The box's local axes (rows), orthonormal.
        axes: [[f32; 3]; 3],
    },
}

/// A contact with an analytic shape: the tangent plane to stand off from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeContact {
    /// Point on the surface.
    pub point: [f32; 3],
    /// Outward unit normal at `point`.
    pub normal: [f32; 3],
    /// `Th - normal.(p - point)`: how far `p` must move along the normal.
    pub depth: f32,
}

#[inline]
pub(crate) fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline]
pub(crate) fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline]
fn add_scaled(a: [f32; 3], t: f32, b: [f32; 3]) -> [f32; 3] {
    [a[0] + t * b[0], a[1] + t * b[1], a[2] + t * b[2]]
}
fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

impl Shape {
    /// Checks the shape: finite values, positive radii and extents, unit plane normal,
    /// orthonormal box axes.
    pub fn validate(&self) -> crate::error::Result<()> {
        use crate::error::{finite3, positive};
        match self {
            Shape::Plane { point, normal } => {
                finite3("plane.point", *point)?;
                finite3("plane.normal", *normal)?;
                if (dot(*normal, *normal).sqrt() - 1.0).abs() > UNIT_TOL {
                    return Err(crate::error::WeftError::param(
                        "plane.normal",
                        format!("{normal:?}"),
                        "must have length 1",
                    ));
                }
            }
            Shape::Sphere { center, radius } => {
                finite3("sphere.center", *center)?;
                positive("sphere.radius", *radius)?;
            }
            Shape::Capsule { a, b, radius } => {
                finite3("capsule.a", *a)?;
                finite3("capsule.b", *b)?;
                positive("capsule.radius", *radius)?;
            }
            Shape::Box { center, half, axes } => {
                finite3("box.center", *center)?;
                for h in half {
                    positive("box.half_extents", *h)?;
                }
                for (i, r) in axes.iter().enumerate() {
                    finite3("box.axes", *r)?;
                    for (j, s) in axes.iter().enumerate() {
                        let want = if i == j { 1.0 } else { 0.0 };
                        if (dot(*r, *s) - want).abs() > UNIT_TOL {
                            return Err(crate::error::WeftError::param(
                                "box.axes",
                                format!("{axes:?}"),
                                "must be orthonormal",
                            ));
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// A plane through `point` with normal `normal` (normalised here; must not be zero).
    pub fn plane(point: [f32; 3], normal: [f32; 3]) -> crate::error::Result<Shape> {
        let l = dot(normal, normal).sqrt();
        if !(l.is_finite() && l > 0.0) {
            return Err(crate::error::WeftError::param(
                "plane.normal",
                format!("{normal:?}"),
                "must be finite and not zero",
            ));
        }
        let s = Shape::Plane {
            point,
            normal: normal.map(|c| c / l),
        };
        s.validate()?;
        Ok(s)
    }

    /// Axes of a box rotated by `deg` degrees about x, then y, then z.
    pub fn axes_from_euler_deg(deg: [f32; 3]) -> [[f32; 3]; 3] {
        let [a, b, c] = deg.map(|d| (d as f64).to_radians());
        let rx = |v: [f64; 3]| [v[0], v[1] * a.cos() - v[2] * a.sin(), v[1] * a.sin() + v[2] * a.cos()];
        let ry = |v: [f64; 3]| [v[0] * b.cos() + v[2] * b.sin(), v[1], -v[0] * b.sin() + v[2] * b.cos()];
        let rz = |v: [f64; 3]| [v[0] * c.cos() - v[1] * c.sin(), v[0] * c.sin() + v[1] * c.cos(), v[2]];
        let e = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        e.map(|v| rz(ry(rx(v))).map(|x| x as f32))
    }

    /// The shape moved by `d`.
    pub fn translated(&self, d: [f32; 3]) -> Shape {
        let m = |q: [f32; 3]| add_scaled(q, 1.0, d);
        match self {
            Shape::Plane { point, normal } => Shape::Plane {
                point: m(*point),
                normal: *normal,
            },
            Shape::Sphere { center, radius } => Shape::Sphere {
                center: m(*center),
                radius: *radius,
            },
            Shape::Capsule { a, b, radius } => Shape::Capsule {
                a: m(*a),
                b: m(*b),
                radius: *radius,
            },
            Shape::Box { center, half, axes } => Shape::Box {
                center: m(*center),
                half: *half,
                axes: *axes,
            },
        }
    }

    /// Signed distance of `q` to the surface (negative inside).
    pub fn signed_distance(&self, q: [f32; 3]) -> f32 {
        match self {
            Shape::Plane { point, normal } => dot(*normal, sub(q, *point)),
            Shape::Sphere { center, radius } => dot(sub(q, *center), sub(q, *center)).sqrt() - radius,
            Shape::Capsule { a, b, radius } => {
                let s = closest_on_segment(q, *a, *b);
                dot(sub(q, s), sub(q, s)).sqrt() - radius
            }
            Shape::Box { center, half, axes } => {
                let l = to_local(axes, sub(q, *center));
                let d = [0, 1, 2].map(|k| l[k].abs() - half[k]);
                let out = d.map(|v| v.max(0.0));
                dot(out, out).sqrt() + d[0].max(d[1]).max(d[2]).min(0.0)
            }
        }
    }

    /// The contact of the step `x -> p` (in the shape's frame) with thickness `th`, found
    /// within `reach >= th` of the surface (module doc).
    pub fn contact(&self, x: [f32; 3], p: [f32; 3], th: f32, reach: f32) -> Option<ShapeContact> {
        let make = |point: [f32; 3], normal: [f32; 3]| ShapeContact {
            point,
            normal,
            depth: th - dot(normal, sub(p, point)),
        };
        match self {
            Shape::Plane { point, normal } => {
                let h = dot(*normal, sub(p, *point));
                (h < reach).then(|| make(add_scaled(p, -h, *normal), *normal))
            }
            Shape::Sphere { center, radius } => ball_contact(*center, *radius, x, p, th, reach).map(|(q, n)| make(q, n)),
            Shape::Capsule { a, b, radius } => {
                let s = closest_on_segment(p, *a, *b);
                if let Some(c) = ball_contact(s, *radius, x, p, th, reach).filter(|_| dist2(p, s) < sq(radius + reach)) {
                    return Some(make(c.0, c.1));
                }
                let s = closest_axis_point_to_path(*a, *b, x, p);
                ball_contact(s, *radius, x, p, th, reach).map(|(q, n)| make(q, n))
            }
            Shape::Box { center, half, axes } => box_contact(*center, *half, axes, x, p, th, reach).map(|(q, n)| make(q, n)),
        }
    }
}

/// A unit vector orthogonal to `n` (for rendering planes and tests).
pub fn any_orthogonal(n: [f32; 3]) -> [f32; 3] {
    let t = if n[0].abs() < 0.9 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
    let c = cross(n, t);
    let l = dot(c, c).sqrt();
    c.map(|k| k / l)
}

#[cfg(test)]
mod tests;
