//! Loading mesh obstacles from Wavefront OBJ files through the `tobj` crate.
//!
//! Every model in the file is merged into one [`TriMesh`]; polygons are triangulated by
//! `tobj` (fan triangulation); normals, texture coordinates and materials are ignored (face
//! normals come from the winding). The merged mesh goes through [`TriMesh::new`]'s checks, and
//! errors name the file.

use crate::obstacles::mesh::{MeshReport, TriMesh};
use crate::{Result, WeftError};
use std::path::Path;

impl TriMesh {
    /// Loads every model of an OBJ file (polygons triangulated by `tobj`) into one mesh. The file
    /// must be a regular file of at most [`crate::files::OBJ_LIMIT`] bytes.
    pub fn from_obj(path: impl AsRef<Path>) -> Result<(TriMesh, MeshReport)> {
        let path = path.as_ref();
        let bytes = crate::files::read_limited(path, crate::files::OBJ_LIMIT, "OBJ mesh")?;
        TriMesh::from_obj_bytes(&bytes, &path.display().to_string())
    }

    /// Loads OBJ text from any reader (at most [`crate::files::OBJ_LIMIT`] bytes); `name`
    /// labels errors. As [`TriMesh::from_obj`].
    pub fn from_obj_reader(reader: &mut impl std::io::BufRead, name: &str) -> Result<(TriMesh, MeshReport)> {
        let raw = crate::files::read_to_limit(reader, crate::files::OBJ_LIMIT, "OBJ mesh", name, 0)?;
        TriMesh::from_obj_bytes(&raw, name)
    }

    /// Loads OBJ text held in memory; `name` labels errors. Material libraries are ignored,
    /// and texture coordinates and normals are removed before parsing ([`positions_only`]):
    /// weft uses neither, and `tobj` overflows on some out-of-range texture indices.
    fn from_obj_bytes(raw: &[u8], name: &str) -> Result<(TriMesh, MeshReport)> {
        let text = positions_only(raw);
        let reader = &mut std::io::Cursor::new(text);
        let opts = tobj::LoadOptions {
            triangulate: true,
            single_index: false,
            ..Default::default()
        };
        let named = |reason: String| WeftError::InvalidMesh {
            source_name: Some(name.to_string()),
            reason,
        };
        let (models, _materials) = tobj::load_obj_buf(reader, &opts, |_| Err(tobj::LoadError::OpenFileFailed)).map_err(|e| match e {
            tobj::LoadError::ReadError => WeftError::Io {
                path: name.to_string(),
                message: e.to_string(),
            },
            other => named(other.to_string()),
        })?;
        let mut vertices = Vec::new();
        let mut faces = Vec::new();
        for m in &models {
            let base = vertices.len() as u32;
            vertices.extend(m.mesh.positions.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
            faces.extend(
                m.mesh
                    .indices
                    .chunks_exact(3)
                    .map(|c| [c[0], c[1], c[2]].map(|i| base.saturating_add(i))),
            );
        }
        TriMesh::new(vertices, faces).map_err(|e| match e {
            WeftError::InvalidMesh { reason, .. } => named(reason),
            other => other,
        })
    }
}

/// OBJ text with `vt` and `vn` lines dropped and face elements `v/vt/vn` cut to `v`. Lines
/// are split into words as `tobj` splits them (Unicode whitespace, so a line that starts with
/// a vertical tab or carriage returns is a keyword line for both); a line that is not UTF-8 is
/// kept as it is (`tobj` refuses it).
pub fn positions_only(raw: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(raw.len());
    for line in raw.split(|b| *b == b'\n') {
        let Ok(text) = std::str::from_utf8(line) else {
            out.extend_from_slice(line);
            out.push(b'\n');
            continue;
        };
        let mut words = text.split_whitespace();
        match words.next() {
            Some("vt" | "vn") => continue,
            Some("f") => {
                out.push(b'f');
                for w in words {
                    out.push(b' ');
                    out.extend_from_slice(w.split('/').next().unwrap_or("").as_bytes());
                }
            }
            _ => out.extend_from_slice(line),
        }
        out.push(b'\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn obj_loads_and_triangulates() {
        let dir = std::env::temp_dir().join(format!("weft_mesh_obj_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("quad.obj");
        std::fs::write(&p, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").unwrap();
        let (m, r) = TriMesh::from_obj(&p).unwrap();
        assert_eq!(m.face_count(), 2);
        assert_eq!(r.boundary_edges, 4);
        let e = TriMesh::from_obj(dir.join("missing.obj")).unwrap_err();
        assert!(matches!(e, WeftError::Io { .. }), "{e}");
        std::fs::write(&p, "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 7\n").unwrap();
        assert!(TriMesh::from_obj(&p).is_err());
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn texture_and_normal_indices_are_ignored() {
        // A negative relative texture index made `tobj` overflow (found by fuzzing).
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/-3/1 2/-99999999999/1 3//1\n";
        let (m, _) = TriMesh::from_obj_reader(&mut text.as_bytes(), "t.obj").unwrap();
        assert_eq!(m.face_count(), 1);
        assert_eq!(positions_only(b"  vt 1 2\nf 1/2/3\t4//5 6\r\nvn 0 0 1"), b"f 1 4 6\n".to_vec());
        // Words split as tobj splits them: a vertical tab or carriage returns before the
        // keyword (found by fuzzing: tobj overflowed on the texture index it still saw).
        let text = "\x0bf 1/-3 2\nv 4 0 0\n\r\r\rvt 0 0";
        assert_eq!(positions_only(text.as_bytes()), b"f 1 2\nv 4 0 0\n".to_vec());
        assert!(TriMesh::from_obj_reader(&mut text.as_bytes(), "t.obj").is_err());
    }
}
