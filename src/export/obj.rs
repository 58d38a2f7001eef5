//! Wavefront OBJ: one file per frame, positions and triangles.

use std::fmt::Write as _;
use std::path::Path;

use crate::error::Result;
use crate::files::write_atomic;

/// Writes positions and triangles as a Wavefront OBJ file (atomically).
pub fn write_obj(path: &Path, positions: &[[f32; 3]], triangles: &[[u32; 3]]) -> Result<()> {
    let mut s = String::with_capacity(positions.len() * 32 + triangles.len() * 24);
    s.push_str("# weft frame\n");
    for p in positions {
        let _ = writeln!(s, "v {} {} {}", p[0], p[1], p[2]);
    }
    for t in triangles {
        let _ = writeln!(s, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    write_atomic(path, s.as_bytes())
}
