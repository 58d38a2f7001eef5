//! The binary chunk of a `.glb` and the buffer views and accessors that describe it, written
//! together (the format is described in [`super`]).

use serde_json::{json, Value};

/// glTF component type: `f32`.
const FLOAT: u32 = 5126;
/// glTF component type: `u32`.
const UNSIGNED_INT: u32 = 5125;
/// Buffer view target: vertex attributes.
const ARRAY_BUFFER: u32 = 34962;
/// Buffer view target: indices.
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
/// The binary chunk and the JSON arrays that describe it, built together.
#[derive(Default)]
pub(super) struct Builder {
    pub(super) bin: Vec<u8>,
    pub(super) views: Vec<Value>,
    pub(super) accessors: Vec<Value>,
}

impl Builder {
    /// Appends floats as a new buffer view and accessor; returns the accessor index.
    pub(super) fn floats(&mut self, data: impl Iterator<Item = f32>, kind: &str, width: usize, target: Option<u32>, bounds: bool) -> usize {
        let start = self.bin.len();
        let mut lo = vec![f32::INFINITY; width];
        let mut hi = vec![f32::NEG_INFINITY; width];
        for (i, v) in data.enumerate() {
            self.bin.extend_from_slice(&v.to_le_bytes());
            lo[i % width] = lo[i % width].min(v);
            hi[i % width] = hi[i % width].max(v);
        }
        let count = (self.bin.len() - start) / (4 * width);
        let mut acc = json!({
            "bufferView": self.view(start, target),
            "componentType": FLOAT,
            "count": count,
            "type": kind,
        });
        if bounds {
            acc["min"] = json!(lo);
            acc["max"] = json!(hi);
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    pub(super) fn vec3s(&mut self, v: impl Iterator<Item = [f32; 3]>, bounds: bool) -> usize {
        self.floats(v.flat_map(|p| p.into_iter()), "VEC3", 3, Some(ARRAY_BUFFER), bounds)
    }

    pub(super) fn indices(&mut self, idx: &[u32]) -> usize {
        let start = self.bin.len();
        for i in idx {
            self.bin.extend_from_slice(&i.to_le_bytes());
        }
        let view = self.view(start, Some(ELEMENT_ARRAY_BUFFER));
        self.accessors.push(json!({
            "bufferView": view,
            "componentType": UNSIGNED_INT,
            "count": idx.len(),
            "type": "SCALAR",
        }));
        self.accessors.len() - 1
    }

    pub(super) fn view(&mut self, start: usize, target: Option<u32>) -> usize {
        let mut v = json!({ "buffer": 0, "byteOffset": start, "byteLength": self.bin.len() - start });
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.views.push(v);
        self.views.len() - 1
    }
}

/// A unit normal (zero becomes `+y`).
pub(super) fn unit(n: [f32; 3]) -> [f32; 3] {
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if l > 0.0 && l.is_finite() {
        n.map(|c| c / l)
    } else {
        [0.0, 1.0, 0.0]
    }
}

pub(super) fn delta(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
