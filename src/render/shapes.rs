//! Ready-made triangle meshes for obstacles and test scenes: sphere, box, capsule, plane.
//!
//! Every shape is wound counter-clockwise seen from outside, so `(p1 - p0) × (p2 - p0)` points
//! out of the solid. Round shapes are surfaces of revolution ("lathes"): rings of `segments`
//! vertices at polar angles `θ` around an axis, `p = c(θ) + r (cos θ · axis + sin θ (cos φ · u +
//! sin φ · v))`, with one vertex at each pole and no duplicated seam, so smooth normals have no
//! crease. Boxes have four vertices per face so their edges stay sharp.

use super::math::{add, cross, normalize, normalize_or, scale, sub};

/// Vertex positions and triangles of a mesh.
pub type Shape = (Vec<[f32; 3]>, Vec<[u32; 3]>);

/// Unit vectors `u, v` with `u × v = n`.
fn basis(n: [f32; 3]) -> ([f32; 3], [f32; 3]) {
    let helper = if n[1].abs() < 0.9 { [0.0, 1.0, 0.0] } else { [1.0, 0.0, 0.0] };
    let u = normalize_or(cross(n, helper), [1.0, 0.0, 0.0]);
    (u, cross(n, u))
}

/// A ring of the lathe: centre, `cos θ`, `sin θ`.
type Ring = ([f32; 3], f32, f32);

/// Builds a closed surface of revolution from its rings (top to bottom) and two poles.
fn lathe(axis: [f32; 3], radius: f32, segments: usize, rings: &[Ring], top: [f32; 3], bottom: [f32; 3]) -> Shape {
    let (u, v) = basis(axis);
    let mut positions = vec![top];
    for &(c, cos_t, sin_t) in rings {
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            let radial = add(scale(u, phi.cos()), scale(v, phi.sin()));
            let dir = add(scale(axis, cos_t), scale(radial, sin_t));
            positions.push(add(c, scale(dir, radius)));
        }
    }
    positions.push(bottom);
    let last = (positions.len() - 1) as u32;
    let at = |ring: usize, j: usize| (1 + ring * segments + j % segments) as u32;
    let mut triangles = Vec::new();
    for j in 0..segments {
        triangles.push([0, at(0, j), at(0, j + 1)]);
        for r in 0..rings.len() - 1 {
            triangles.push([at(r, j), at(r + 1, j), at(r + 1, j + 1)]);
            triangles.push([at(r, j), at(r + 1, j + 1), at(r, j + 1)]);
        }
        triangles.push([at(rings.len() - 1, j), last, at(rings.len() - 1, j + 1)]);
    }
    (positions, triangles)
}

/// A sphere with `segments` vertices around (at least 3) and `segments / 2` bands.
pub fn uv_sphere(center: [f32; 3], radius: f32, segments: u32) -> Shape {
    let segments = segments.max(3) as usize;
    let bands = (segments / 2).max(2);
    let rings: Vec<Ring> = (1..bands)
        .map(|i| {
            let theta = std::f32::consts::PI * i as f32 / bands as f32;
            (center, theta.cos(), theta.sin())
        })
        .collect();
    let axis = [0.0, 1.0, 0.0];
    let top = add(center, scale(axis, radius));
    let bottom = sub(center, scale(axis, radius));
    lathe(axis, radius, segments, &rings, top, bottom)
}

/// A capsule: the segment `a`-`b` swept by a sphere of `radius`, with `segments` vertices
/// around. When `a == b` the axis is taken as +y.
pub fn capsule(a: [f32; 3], b: [f32; 3], radius: f32, segments: u32) -> Shape {
    let segments = segments.max(3) as usize;
    let axis = normalize(sub(b, a)).unwrap_or([0.0, 1.0, 0.0]);
    let per_cap = (segments / 4).max(2);
    let half_pi = std::f32::consts::FRAC_PI_2;
    let mut rings: Vec<Ring> = Vec::new();
    for k in 1..=per_cap {
        let theta = half_pi * k as f32 / per_cap as f32;
        rings.push((b, theta.cos(), theta.sin()));
    }
    for k in 0..per_cap {
        let theta = half_pi + half_pi * k as f32 / per_cap as f32;
        rings.push((a, theta.cos(), theta.sin()));
    }
    let top = add(b, scale(axis, radius));
    let bottom = sub(a, scale(axis, radius));
    lathe(axis, radius, segments, &rings, top, bottom)
}

/// An axis-aligned box with flat faces (four vertices per face).
pub fn box_mesh(center: [f32; 3], half_extents: [f32; 3]) -> Shape {
    let mut positions = Vec::with_capacity(24);
    let mut triangles = Vec::with_capacity(12);
    for axis in 0..3 {
        for sign in [1.0f32, -1.0] {
            let mut n = [0.0; 3];
            n[axis] = sign;
            let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
            // u along axis a, v along axis b with u × v = n (flip v for the negative face).
            let mut u = [0.0; 3];
            u[a] = half_extents[a];
            let mut v = [0.0; 3];
            v[b] = half_extents[b] * sign;
            let c = add(center, scale(n, half_extents[axis]));
            let base = positions.len() as u32;
            positions.push(sub(sub(c, u), v));
            positions.push(sub(add(c, u), v));
            positions.push(add(add(c, u), v));
            positions.push(add(sub(c, u), v));
            triangles.push([base, base + 1, base + 2]);
            triangles.push([base, base + 2, base + 3]);
        }
    }
    (positions, triangles)
}

/// A square of side `2 half_size` through `point`, facing `normal` (+y if it is zero).
pub fn plane_quad(point: [f32; 3], normal: [f32; 3], half_size: f32) -> Shape {
    let n = normalize(normal).unwrap_or([0.0, 1.0, 0.0]);
    let (u, v) = basis(n);
    let (u, v) = (scale(u, half_size), scale(v, half_size));
    let positions = vec![
        sub(sub(point, u), v),
        sub(add(point, u), v),
        add(add(point, u), v),
        add(sub(point, u), v),
    ];
    (positions, vec![[0, 1, 2], [0, 2, 3]])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::math::dot;

    /// Every face normal points away from `inside`, every index is valid, and the area-weighted
    /// normals sum to about zero (a closed surface).
    fn check_closed_outward(shape: &Shape, inside: [f32; 3]) {
        let (p, t) = shape;
        let mut total = [0.0f32; 3];
        for tri in t {
            assert!(tri.iter().all(|&i| (i as usize) < p.len()));
            let [a, b, c] = tri.map(|i| p[i as usize]);
            let face = cross(sub(b, a), sub(c, a));
            let centroid = scale(add(add(a, b), c), 1.0 / 3.0);
            assert!(dot(face, sub(centroid, inside)) >= 0.0, "inward face {tri:?}");
            total = add(total, face);
        }
        assert!(total.iter().all(|c| c.abs() < 1e-3), "{total:?}");
    }

    #[test]
    fn shapes_are_closed_and_wound_outward() {
        let s = uv_sphere([1.0, 2.0, 3.0], 0.5, 24);
        check_closed_outward(&s, [1.0, 2.0, 3.0]);
        assert!(s
            .0
            .iter()
            .all(|&p| (crate::render::math::length(sub(p, [1.0, 2.0, 3.0])) - 0.5).abs() < 1e-5));
        check_closed_outward(&box_mesh([0.0; 3], [1.0, 2.0, 3.0]), [0.0; 3]);
        let cap = capsule([0.0; 3], [1.0, 1.0, 0.0], 0.3, 16);
        check_closed_outward(&cap, [0.5, 0.5, 0.0]);
        check_closed_outward(&uv_sphere([0.0; 3], 1.0, 0), [0.0; 3]);
    }

    #[test]
    fn plane_faces_its_normal() {
        let (p, t) = plane_quad([0.0, 1.0, 0.0], [0.0, 0.0, 2.0], 3.0);
        for tri in t {
            let [a, b, c] = tri.map(|i| p[i as usize]);
            let n = normalize(cross(sub(b, a), sub(c, a))).unwrap();
            assert!((n[2] - 1.0).abs() < 1e-6);
        }
        assert!(p.iter().all(|q| (q[1] - 1.0).abs() <= 3.0 + 1e-6 && q[2] == 0.0));
    }
}
