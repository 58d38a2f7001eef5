//! Mesh preparation: index checks, the triangles that can be drawn, smooth vertex normals.
//!
//! The smooth normal of a vertex is the sum of the (unnormalized) cross products
//! `(p1 - p0) × (p2 - p0)` of the triangles around it, which weights each face by its area,
//! normalized at the end. A triangle with a non-finite corner is skipped (never drawn, never
//! contributes a normal); an index past the vertex list is an error.

use super::math::{add, cross, is_finite3, normalize, sub};
use super::MeshItem;
use crate::{Result, WeftError};

/// A mesh ready to draw.
pub(crate) struct PreparedMesh<'a> {
    /// The mesh's vertex positions (borrowed).
    pub positions: &'a [[f32; 3]],
    /// Unit vertex normals (zero where no drawable triangle touches the vertex).
    pub normals: Vec<[f32; 3]>,
    /// The triangles with three finite, in-range corners and non-zero area.
    pub triangles: Vec<[u32; 3]>,
    /// Base colour, linear light.
    pub color: [f32; 3],
}

/// Checks the indices of `mesh` (item number `which` in the scene) and prepares it.
pub(crate) fn prepare(mesh: &MeshItem, which: usize) -> Result<PreparedMesh<'_>> {
    let n = mesh.positions.len();
    let mut normals = vec![[0.0f32; 3]; n];
    let mut triangles = Vec::with_capacity(mesh.triangles.len());
    for t in &mesh.triangles {
        if let Some(&bad) = t.iter().find(|&&i| i as usize >= n) {
            return Err(WeftError::InvalidMesh {
                source_name: Some(format!("render mesh {which}")),
                reason: format!("vertex index {bad} is out of range (there are {n} vertices)"),
            });
        }
        let [p0, p1, p2] = t.map(|i| mesh.positions[i as usize]);
        if !(is_finite3(p0) && is_finite3(p1) && is_finite3(p2)) {
            continue;
        }
        let face = cross(sub(p1, p0), sub(p2, p0));
        if !is_finite3(face) || face == [0.0; 3] {
            continue;
        }
        for &i in t {
            normals[i as usize] = add(normals[i as usize], face);
        }
        triangles.push(*t);
    }
    for nrm in &mut normals {
        *nrm = normalize(*nrm).unwrap_or([0.0; 3]);
    }
    Ok(PreparedMesh {
        positions: &mesh.positions,
        normals,
        triangles,
        color: super::shade::color_to_linear(mesh.color),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normals_are_unit_and_bad_triangles_are_skipped_or_rejected() {
        let mesh = MeshItem {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [f32::NAN, 0.0, 0.0]],
            triangles: vec![[0, 1, 2], [0, 1, 3], [0, 0, 1]],
            color: [255; 3],
        };
        let p = prepare(&mesh, 0).unwrap();
        assert_eq!(p.triangles, vec![[0, 1, 2]]);
        assert_eq!(p.normals[0], [0.0, 0.0, 1.0]);
        assert_eq!(p.normals[3], [0.0; 3]);
        let bad = MeshItem {
            triangles: vec![[0, 1, 9]],
            ..mesh
        };
        assert!(matches!(prepare(&bad, 2), Err(WeftError::InvalidMesh { .. })));
    }
}
