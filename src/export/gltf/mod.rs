//! Binary glTF 2.0 (`.glb`) of an animated run: meshes and line sets whose vertices move
//! from frame to frame.
//!
//! The writer takes plain arrays, one [`GltfMesh`] per object: positions per frame, optional
//! normals per frame, and triangles or line strips. It knows nothing of `World`; the caller
//! gathers the frames. Each mesh becomes one node with one primitive and a material of its
//! colour; the axes are glTF's own (y up, metres), which are weft's.
//!
//! **Animation by morph targets.** A mesh that moves stores its first frame as the base
//! geometry and every later frame as one morph target (the displacement from the base, for
//! `POSITION` and `NORMAL`). One animation channel per moving mesh drives the node's morph
//! weights: at the time of frame `k` the weight of target `k` is 1 and every other weight is
//! 0, and the sampler interpolates `LINEAR`ly, so between two kept frames the mesh blends
//! smoothly from one to the next and plays well at any frame rate. Blender imports the targets
//! as shape keys (named `frame_1`, `frame_2`, ... from `mesh.extras.targetNames`) with their
//! weights keyed on the timeline; three.js's `GLTFLoader` plays them as a morph animation.
//! The alternative, one mesh per frame with node scale keyed between 0 and 1, stores the same
//! vertex data (the index buffer is shared either way), but cannot interpolate between frames,
//! and Blender imports it as one object per frame. Morph targets cost `4 F (F - 1)` extra
//! bytes of weights for `F` frames (40 kB at 100 frames), small beside the vertex data. A mesh
//! whose frames are all identical, or that is given one frame, is written once with no
//! targets.
//!
//! Normals are normalised on the way out (glTF requires unit normals); a zero normal becomes
//! `+y`. Every value must be finite. Files larger than [`MAX_GLB_BYTES`] are refused before
//! anything is allocated.

use std::ops::Range;
use std::path::Path;

use serde_json::json;

use crate::error::{Result, WeftError};
use crate::files::write_atomic;

mod buffer;

use buffer::{delta, unit, Builder};

/// The largest `.glb` [`glb_bytes`] writes: 512 MiB. A run with more vertex data is refused
/// with an error (keep fewer frames, or fewer particles).
pub const MAX_GLB_BYTES: u64 = 512 << 20;

/// Primitive mode: lines (pairs of indices).
const MODE_LINES: u32 = 1;
/// Primitive mode: triangles.
const MODE_TRIANGLES: u32 = 4;

/// What a mesh's vertices are connected into.
#[derive(Clone, Copy, Debug)]
pub enum Topology<'a> {
    /// Triangles, indices into the mesh's vertices, counter-clockwise seen from the front.
    Triangles(&'a [[u32; 3]]),
    /// Polylines, each a range of consecutive vertices (written as a glTF `LINES` primitive).
    LineStrips(&'a [Range<u32>]),
}

/// One object of the file.
#[derive(Clone, Debug)]
pub struct GltfMesh<'a> {
    /// Node and mesh name.
    pub name: &'a str,
    /// Base colour, linear RGBA in `[0, 1]`.
    pub color: [f32; 4],
    /// How the vertices are connected.
    pub topology: Topology<'a>,
    /// Vertex positions: one slice per frame (every slice the same length), or a single slice
    /// for a mesh that does not move.
    pub positions: Vec<&'a [[f32; 3]]>,
    /// Vertex normals, shaped like `positions`, or empty for none.
    pub normals: Vec<&'a [[f32; 3]]>,
}

/// A mesh checked and prepared: its index list and whether it moves.
struct Prepared<'m, 'a> {
    mesh: &'m GltfMesh<'a>,
    indices: Vec<u32>,
    mode: u32,
    vertices: usize,
    animated: bool,
}

fn bad(name: &str, value: impl std::fmt::Display, reason: &str) -> WeftError {
    WeftError::param(format!("gltf.{name}"), value, reason)
}

fn prepare<'m, 'a>(m: &'m GltfMesh<'a>, frames: usize) -> Result<Prepared<'m, 'a>> {
    let name = m.name;
    let Some(first) = m.positions.first() else {
        return Err(bad(name, "no frames", "a mesh needs positions for one frame or for every frame"));
    };
    let vertices = first.len();
    if m.positions.len() != 1 && m.positions.len() != frames {
        return Err(bad(
            name,
            format!("{} frames of positions", m.positions.len()),
            &format!("must be 1 (a still mesh) or the number of frame times, {frames}"),
        ));
    }
    if !m.normals.is_empty() && m.normals.len() != m.positions.len() {
        return Err(bad(
            name,
            format!("{} frames of normals", m.normals.len()),
            "must match the frames of positions",
        ));
    }
    for (k, p) in m.positions.iter().enumerate() {
        if p.len() != vertices {
            return Err(bad(
                name,
                format!("frame {k} has {} vertices", p.len()),
                &format!("every frame must have {vertices}"),
            ));
        }
        if let Some(i) = p.iter().position(|v| !v.iter().all(|c| c.is_finite())) {
            return Err(bad(name, format!("frame {k} vertex {i} = {:?}", p[i]), "positions must be finite"));
        }
    }
    for (k, n) in m.normals.iter().enumerate() {
        if n.len() != vertices {
            return Err(bad(
                name,
                format!("frame {k} has {} normals", n.len()),
                &format!("every frame must have {vertices}"),
            ));
        }
        if let Some(i) = n.iter().position(|v| !v.iter().all(|c| c.is_finite())) {
            return Err(bad(name, format!("frame {k} normal {i} = {:?}", n[i]), "normals must be finite"));
        }
    }
    if !m.color.iter().all(|c| (0.0..=1.0).contains(c)) {
        return Err(bad(name, format!("colour {:?}", m.color), "components must be in [0, 1]"));
    }
    let in_range = |i: u32| (i as usize) < vertices;
    let (indices, mode) = match m.topology {
        Topology::Triangles(t) => {
            if let Some(bad_t) = t.iter().find(|t| !t.iter().all(|&i| in_range(i))) {
                return Err(bad(
                    name,
                    format!("triangle {bad_t:?}"),
                    &format!("indices must be below {vertices}"),
                ));
            }
            (t.iter().flatten().copied().collect(), MODE_TRIANGLES)
        }
        Topology::LineStrips(strips) => {
            let mut idx = Vec::new();
            for s in strips {
                if s.start > s.end || s.end as usize > vertices {
                    return Err(bad(
                        name,
                        format!("line strip {s:?}"),
                        &format!("must be a range within 0..{vertices}"),
                    ));
                }
                for i in s.start..s.end.saturating_sub(1).max(s.start) {
                    idx.extend_from_slice(&[i, i + 1]);
                }
            }
            (idx, MODE_LINES)
        }
    };
    let animated = m.positions.len() > 1 && (m.positions.iter().any(|p| p != first) || m.normals.iter().any(|n| *n != m.normals[0]));
    Ok(Prepared {
        mesh: m,
        indices,
        mode,
        vertices,
        animated,
    })
}

/// Bytes of the binary chunk for these meshes (every piece is a multiple of 4 bytes).
fn bin_size(prepared: &[Prepared], frames: usize) -> u64 {
    let f = frames as u64;
    let mut total = 0u64;
    for p in prepared {
        let attrs = if p.mesh.normals.is_empty() { 1 } else { 2 };
        let per_frame = p.vertices as u64 * 12 * attrs;
        total = total.saturating_add(4 * p.indices.len() as u64).saturating_add(per_frame);
        if p.animated {
            total = total
                .saturating_add(per_frame.saturating_mul(f - 1))
                .saturating_add(4 * f * (f - 1));
        }
    }
    if prepared.iter().any(|p| p.animated) {
        total = total.saturating_add(4 * f);
    }
    total
}

/// Builds the `.glb` bytes of `meshes` animated over `times` (seconds, one per frame, at least
/// one, starting at or after 0 and strictly increasing).
///
/// ```
/// use weft::export::{glb_bytes, GltfMesh, Topology};
///
/// let tri = [[0, 1, 2]];
/// let f0 = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
/// let f1 = [[0.0, -0.5, 0.0], [1.0, -0.5, 0.0], [0.0, 0.5, 0.0]];
/// let mesh = GltfMesh {
///     name: "cloth",
///     color: [0.8, 0.2, 0.2, 1.0],
///     topology: Topology::Triangles(&tri),
///     positions: vec![&f0[..], &f1[..]],
///     normals: vec![],
/// };
/// let glb = glb_bytes(&[mesh], &[0.0, 0.5])?;
/// assert_eq!(&glb[0..4], b"glTF");
/// assert_eq!(glb.len() % 4, 0);
/// # Ok::<(), weft::WeftError>(())
/// ```
pub fn glb_bytes(meshes: &[GltfMesh], times: &[f32]) -> Result<Vec<u8>> {
    let frames = times.len();
    if frames == 0 {
        return Err(bad("times", "[]", "at least one frame time is needed"));
    }
    if !times.iter().all(|t| t.is_finite()) || times[0] < 0.0 || times.windows(2).any(|w| w[1] <= w[0]) {
        return Err(bad(
            "times",
            format!("{times:?}"),
            "must be finite, start at 0 or later and strictly increase",
        ));
    }
    let prepared = meshes.iter().map(|m| prepare(m, frames)).collect::<Result<Vec<_>>>()?;
    // Meshes with nothing to draw are left out (glTF accessors may not be empty).
    let prepared: Vec<_> = prepared.into_iter().filter(|p| p.vertices > 0 && !p.indices.is_empty()).collect();
    let size = bin_size(&prepared, frames);
    // The JSON is small beside the data; allow it 64 kB plus ~1 kB per morph target.
    let json_bound = 65_536 + 1024 * (frames as u64) * prepared.len() as u64;
    if size.saturating_add(json_bound) > MAX_GLB_BYTES || size > u32::MAX as u64 {
        return Err(bad(
            "size",
            format!("{size} bytes"),
            &format!("exceeds the limit of {MAX_GLB_BYTES} bytes: keep fewer frames or fewer particles"),
        ));
    }
    let mut b = Builder {
        bin: Vec::with_capacity(size as usize),
        ..Default::default()
    };
    let mut json_meshes = Vec::new();
    let mut nodes = Vec::new();
    let mut materials = Vec::new();
    let mut channels = Vec::new();
    let mut samplers = Vec::new();
    let time_acc = if prepared.iter().any(|p| p.animated) {
        Some(b.floats(times.iter().copied(), "SCALAR", 1, None, true))
    } else {
        None
    };
    for (k, p) in prepared.iter().enumerate() {
        let m = p.mesh;
        let indices = b.indices(&p.indices);
        let base = m.positions[0];
        let mut attributes = json!({ "POSITION": b.vec3s(base.iter().copied(), true) });
        let base_n: Option<Vec<[f32; 3]>> = m.normals.first().map(|n| n.iter().map(|&v| unit(v)).collect());
        if let Some(n) = &base_n {
            attributes["NORMAL"] = json!(b.vec3s(n.iter().copied(), false));
        }
        let mut primitive = json!({ "attributes": attributes, "indices": indices, "mode": p.mode, "material": k });
        let mut mesh = json!({ "name": m.name, "primitives": [] });
        if p.animated {
            let mut targets = Vec::with_capacity(frames - 1);
            for f in 1..frames {
                let pos = m.positions[f];
                let mut t = json!({ "POSITION": b.vec3s(pos.iter().zip(base).map(|(a, o)| delta(*a, *o)), true) });
                if let Some(n0) = &base_n {
                    let nf = m.normals[f];
                    t["NORMAL"] = json!(b.vec3s(nf.iter().zip(n0).map(|(a, o)| delta(unit(*a), *o)), false));
                }
                targets.push(t);
            }
            primitive["targets"] = json!(targets);
            mesh["weights"] = json!(vec![0.0f32; frames - 1]);
            mesh["extras"] = json!({ "targetNames": (1..frames).map(|f| format!("frame_{f}")).collect::<Vec<_>>() });
            // Keyframe f: weight of target f - 1 is 1 (frame 0 is the base, all weights 0).
            let weights = (0..frames).flat_map(|f| (1..frames).map(move |t| if t == f { 1.0 } else { 0.0 }));
            let out = b.floats(weights, "SCALAR", 1, None, false);
            samplers.push(json!({ "input": time_acc, "output": out, "interpolation": "LINEAR" }));
            channels.push(json!({ "sampler": samplers.len() - 1, "target": { "node": k, "path": "weights" } }));
        }
        mesh["primitives"] = json!([primitive]);
        json_meshes.push(mesh);
        nodes.push(json!({ "name": m.name, "mesh": k }));
        materials.push(json!({
            "name": m.name,
            "doubleSided": true,
            "pbrMetallicRoughness": { "baseColorFactor": m.color, "metallicFactor": 0.0, "roughnessFactor": 0.8 },
        }));
    }
    debug_assert_eq!(b.bin.len() as u64, size);
    let mut doc = json!({
        "asset": { "version": "2.0", "generator": concat!("weft ", env!("CARGO_PKG_VERSION")) },
        "scene": 0,
        "scenes": [{ "name": "weft", "nodes": (0..nodes.len()).collect::<Vec<_>>() }],
        "nodes": nodes,
    });
    if !json_meshes.is_empty() {
        doc["meshes"] = json!(json_meshes);
        doc["materials"] = json!(materials);
        doc["accessors"] = json!(b.accessors);
        doc["bufferViews"] = json!(b.views);
        doc["buffers"] = json!([{ "byteLength": b.bin.len() }]);
    }
    if !channels.is_empty() {
        doc["animations"] = json!([{ "name": "run", "channels": channels, "samplers": samplers }]);
    }
    let mut json_bytes = serde_json::to_vec(&doc).map_err(|e| bad("json", e, "could not be written"))?;
    while json_bytes.len() % 4 != 0 {
        json_bytes.push(b' ');
    }
    let with_bin = !b.bin.is_empty();
    let total = 12 + 8 + json_bytes.len() as u64 + if with_bin { 8 + b.bin.len() as u64 } else { 0 };
    if total > MAX_GLB_BYTES {
        return Err(bad(
            "size",
            format!("{total} bytes"),
            &format!("exceeds the limit of {MAX_GLB_BYTES} bytes"),
        ));
    }
    let mut out = Vec::with_capacity(total as usize);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json_bytes.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json_bytes);
    if with_bin {
        out.extend_from_slice(&(b.bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&b.bin);
    }
    Ok(out)
}

/// Writes [`glb_bytes`] to `path` (atomically).
pub fn write_glb(path: &Path, meshes: &[GltfMesh], times: &[f32]) -> Result<()> {
    write_atomic(path, &glb_bytes(meshes, times)?)
}
