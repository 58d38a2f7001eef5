//! Where each piece lives in the world's particle arrays: a cloth's grid and a group of strands
//! are contiguous particle ranges, with their triangles (cloth) and the scalp (strands). The
//! scalp's placement and collision kernels are `crate::strands::scalp`.

/// Where one cloth lives in the world's particle arrays.
#[derive(Clone, Debug, PartialEq)]
pub struct ClothInfo {
    /// Index of the cloth's first particle.
    pub first: u32,
    /// Rows of the grid.
    pub rows: u32,
    /// Columns of the grid.
    pub cols: u32,
    /// First triangle of the cloth in `World::triangles`.
    pub first_triangle: u32,
    /// Number of triangles.
    pub triangle_count: u32,
    /// Thickness, m.
    pub thickness: f32,
}

/// Where one group of strands lives in the world's particle arrays.
#[derive(Clone, Debug, PartialEq)]
pub struct StrandInfo {
    /// Index of the group's first particle (the root of strand 0).
    pub first: u32,
    /// Number of strands; strand `s` is `first + s * points .. first + (s + 1) * points`.
    pub count: u32,
    /// Points per strand, root first.
    pub points: u32,
    /// The scalp the roots sit on.
    pub scalp: Scalp,
    /// Strand diameter, m.
    pub thickness: f32,
}

impl StrandInfo {
    /// Particle range of strand `s` (unchecked: `s < count`).
    pub fn strand_range(&self, s: u32) -> std::ops::Range<usize> {
        let a = self.first as usize + (s as usize) * self.points as usize;
        a..a + self.points as usize
    }
}

/// An ellipsoidal scalp patch (a sphere is the special case of equal radii).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Scalp {
    /// Centre, m.
    pub center: [f32; 3],
    /// Semi-axes along x, y (up) and z, m.
    pub radii: [f32; 3],
    /// Polar-angle range of the hair patch, degrees from `+y` (0 = crown, 180 = chin).
    pub polar_degrees: [f32; 2],
}

/// One strand group's collision entry: a particle range and its inflated scalp.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScalpRange {
    /// First particle.
    pub start: usize,
    /// One past the last particle.
    pub end: usize,
    /// Scalp centre.
    pub center: [f32; 3],
    /// Scalp radii plus the margin.
    pub radii: [f32; 3],
}
