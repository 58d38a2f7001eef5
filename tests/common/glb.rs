//! A small reader of binary glTF files for the tests: checks the container and the parts of
//! the JSON the glTF 2.0 specification requires, and decodes accessors.

use serde_json::Value;

/// A parsed `.glb`: its JSON and its binary chunk.
pub struct Glb {
    pub json: Value,
    pub bin: Vec<u8>,
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

/// Parses `bytes`, asserting the header, chunk layout, alignment and the required JSON fields
/// (buffers, buffer views and accessors in range, min/max on every POSITION accessor).
pub fn parse(bytes: &[u8]) -> Glb {
    assert!(bytes.len() >= 20, "too short for a GLB");
    assert_eq!(&bytes[0..4], b"glTF", "magic");
    assert_eq!(u32_at(bytes, 4), 2, "container version");
    assert_eq!(u32_at(bytes, 8) as usize, bytes.len(), "header length");
    assert_eq!(bytes.len() % 4, 0, "file length aligned");
    let json_len = u32_at(bytes, 12) as usize;
    assert_eq!(&bytes[16..20], b"JSON", "first chunk is JSON");
    assert_eq!(json_len % 4, 0, "JSON chunk aligned");
    let json: Value = serde_json::from_slice(&bytes[20..20 + json_len]).expect("JSON chunk parses");
    let mut bin = Vec::new();
    let after = 20 + json_len;
    if after < bytes.len() {
        let bin_len = u32_at(bytes, after) as usize;
        assert_eq!(&bytes[after + 4..after + 8], b"BIN\0", "second chunk is BIN");
        assert_eq!(bin_len % 4, 0, "BIN chunk aligned");
        assert_eq!(after + 8 + bin_len, bytes.len(), "BIN chunk ends the file");
        bin = bytes[after + 8..].to_vec();
    }
    assert_eq!(json["asset"]["version"], "2.0");
    if let Some(buffers) = json["buffers"].as_array() {
        assert_eq!(buffers.len(), 1);
        let len = buffers[0]["byteLength"].as_u64().unwrap() as usize;
        assert!(
            len <= bin.len() && bin.len() - len < 4,
            "buffer length {len} vs chunk {}",
            bin.len()
        );
        assert!(buffers[0].get("uri").is_none(), "the GLB buffer has no uri");
    }
    let views = json["bufferViews"].as_array().cloned().unwrap_or_default();
    for v in &views {
        let off = v["byteOffset"].as_u64().unwrap_or(0) as usize;
        let len = v["byteLength"].as_u64().unwrap() as usize;
        assert_eq!(v["buffer"], 0);
        assert!(len >= 1 && off + len <= bin.len(), "view {v} out of range");
        assert_eq!(off % 4, 0, "view offset aligned");
    }
    for a in json["accessors"].as_array().cloned().unwrap_or_default() {
        let v = &views[a["bufferView"].as_u64().unwrap() as usize];
        let ct = a["componentType"].as_u64().unwrap();
        assert!([5120, 5121, 5122, 5123, 5125, 5126].contains(&ct));
        let width = match a["type"].as_str().unwrap() {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            t => panic!("unexpected type {t}"),
        };
        let count = a["count"].as_u64().unwrap() as usize;
        assert!(count >= 1);
        let off = a["byteOffset"].as_u64().unwrap_or(0) as usize;
        assert!(
            off + count * width * 4 <= v["byteLength"].as_u64().unwrap() as usize,
            "accessor {a} past its view"
        );
    }
    for m in json["meshes"].as_array().cloned().unwrap_or_default() {
        for p in m["primitives"].as_array().unwrap() {
            let pos = p["attributes"]["POSITION"].as_u64().unwrap() as usize;
            let mut positions = vec![pos];
            for t in p["targets"].as_array().cloned().unwrap_or_default() {
                positions.push(t["POSITION"].as_u64().unwrap() as usize);
            }
            for acc in positions {
                let a = &json["accessors"][acc];
                assert!(
                    a["min"].is_array() && a["max"].is_array(),
                    "POSITION accessor {acc} needs min and max"
                );
                let g = Glb {
                    json: json.clone(),
                    bin: bin.clone(),
                };
                let vals = g.vec3(acc);
                for k in 0..3 {
                    let lo = vals.iter().map(|v| v[k]).fold(f32::INFINITY, f32::min);
                    let hi = vals.iter().map(|v| v[k]).fold(f32::NEG_INFINITY, f32::max);
                    assert_eq!(a["min"][k].as_f64().unwrap() as f32, lo);
                    assert_eq!(a["max"][k].as_f64().unwrap() as f32, hi);
                }
            }
        }
    }
    Glb { json, bin }
}

impl Glb {
    fn bytes(&self, acc: usize) -> (&[u8], usize) {
        let a = &self.json["accessors"][acc];
        let v = &self.json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
        let off = v["byteOffset"].as_u64().unwrap_or(0) as usize + a["byteOffset"].as_u64().unwrap_or(0) as usize;
        (&self.bin[off..], a["count"].as_u64().unwrap() as usize)
    }

    /// A FLOAT accessor's values, flat.
    pub fn floats(&self, acc: usize) -> Vec<f32> {
        assert_eq!(self.json["accessors"][acc]["componentType"], 5126);
        let width = match self.json["accessors"][acc]["type"].as_str().unwrap() {
            "SCALAR" => 1,
            "VEC3" => 3,
            t => panic!("unexpected {t}"),
        };
        let (b, n) = self.bytes(acc);
        (0..n * width)
            .map(|i| f32::from_le_bytes(b[4 * i..4 * i + 4].try_into().unwrap()))
            .collect()
    }

    /// A VEC3 FLOAT accessor's values.
    pub fn vec3(&self, acc: usize) -> Vec<[f32; 3]> {
        self.floats(acc).chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
    }

    /// An UNSIGNED_INT accessor's values.
    pub fn u32s(&self, acc: usize) -> Vec<u32> {
        assert_eq!(self.json["accessors"][acc]["componentType"], 5125);
        let (b, n) = self.bytes(acc);
        (0..n)
            .map(|i| u32::from_le_bytes(b[4 * i..4 * i + 4].try_into().unwrap()))
            .collect()
    }

    /// The mesh named `name`'s single primitive.
    pub fn primitive(&self, name: &str) -> Value {
        let m = self.json["meshes"]
            .as_array()
            .unwrap()
            .iter()
            .find(|m| m["name"] == name)
            .unwrap_or_else(|| panic!("no mesh {name}"));
        m["primitives"][0].clone()
    }

    /// Positions of every frame of mesh `name`: the base plus each morph target's displacement.
    pub fn frames(&self, name: &str) -> Vec<Vec<[f32; 3]>> {
        self.frames_of(name, "POSITION")
    }

    /// Like [`Glb::frames`] for any morphed attribute (`POSITION` or `NORMAL`).
    pub fn frames_of(&self, name: &str, attr: &str) -> Vec<Vec<[f32; 3]>> {
        let p = self.primitive(name);
        let base = self.vec3(p["attributes"][attr].as_u64().unwrap() as usize);
        let mut out = vec![base.clone()];
        for t in p["targets"].as_array().cloned().unwrap_or_default() {
            let d = self.vec3(t[attr].as_u64().unwrap() as usize);
            out.push(base.iter().zip(&d).map(|(b, d)| [b[0] + d[0], b[1] + d[1], b[2] + d[2]]).collect());
        }
        out
    }
}
