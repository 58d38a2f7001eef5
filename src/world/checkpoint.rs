//! Checkpoints: the full evolving state of a world plus the scene text that built it, so a
//! run can resume from the file alone and continue bit for bit as if never interrupted.
//!
//! Layout (little-endian): magic `WEFTCKP1`, `u32` format version, `u64` steps, `f64` time,
//! `u64` particle count, `u64` scene length + scene UTF-8 text, then `x y z vx vy vz` as
//! `f32` arrays, then a `u64` FNV-1a hash of everything before it. Files are written to a
//! temporary name and renamed, so a crash never leaves a half-written checkpoint.

use std::path::Path;

use crate::error::{Result, WeftError};
use crate::world::World;

const MAGIC: &[u8; 8] = b"WEFTCKP1";
const VERSION: u32 = 1;

/// A loaded checkpoint.
#[derive(Clone, Debug, PartialEq)]
pub struct Checkpoint {
    /// The scene text the world was built from.
    pub scene: String,
    /// Steps taken.
    pub steps: u64,
    /// Simulated time, s.
    pub time: f64,
    /// Positions and velocities: x, y, z, vx, vy, vz.
    pub state: [Vec<f32>; 6],
}

/// The FNV-1a hash a checkpoint ends with.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h = 0xcbf29ce484222325u64;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x100000001b3);
    }
    h
}

use crate::files::write_atomic;

impl World {
    /// The checkpoint of the current state.
    pub fn checkpoint(&self, scene_text: &str) -> Checkpoint {
        let n = self.particle_count();
        let p = &self.particles;
        Checkpoint {
            scene: scene_text.to_string(),
            steps: self.steps,
            time: self.time,
            state: [&p.x, &p.y, &p.z, &p.vx, &p.vy, &p.vz].map(|a| a[..n].to_vec()),
        }
    }

    /// Restores positions, velocities, time and step count from a checkpoint of a world with
    /// the same topology. What mesh obstacles kept from earlier steps (face memories, face
    /// caches) is forgotten, as in a run resumed from the file.
    pub fn restore(&mut self, c: &Checkpoint) -> Result<()> {
        let n = self.particle_count();
        for (k, a) in c.state.iter().enumerate() {
            if a.len() != n {
                return Err(WeftError::BufferLength {
                    name: ["x", "y", "z", "vx", "vy", "vz"][k],
                    got: a.len(),
                    expected: n,
                });
            }
            if let Some(bad) = a.iter().position(|v| !v.is_finite()) {
                return Err(WeftError::param("checkpoint state", format!("particle {bad}"), "non-finite value"));
            }
        }
        let p = &mut self.particles;
        for (dst, src) in [&mut p.x, &mut p.y, &mut p.z, &mut p.vx, &mut p.vy, &mut p.vz]
            .into_iter()
            .zip(&c.state)
        {
            dst[..n].copy_from_slice(src);
        }
        p.px.copy_from_slice(&p.x);
        p.py.copy_from_slice(&p.y);
        p.pz.copy_from_slice(&p.z);
        self.steps = c.steps;
        self.time = c.time;
        self.obstacles.forget_history();
        Ok(())
    }
}

/// Reads a checkpoint body front to back; running past the end is an error, never a panic.
struct Reader<'a> {
    body: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn bytes(&mut self, k: usize) -> Result<&[u8]> {
        let end = self.at.checked_add(k);
        let s = end.and_then(|e| self.body.get(self.at..e));
        let s = s.ok_or_else(|| WeftError::Scene("not a valid weft checkpoint: truncated".into()))?;
        self.at += k;
        Ok(s)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N]> {
        let s = self.bytes(N)?;
        Ok(std::array::from_fn(|i| s[i]))
    }
}

impl Checkpoint {
    /// Encodes the checkpoint.
    pub fn to_bytes(&self) -> Vec<u8> {
        let n = self.state[0].len();
        let mut b = Vec::with_capacity(64 + self.scene.len() + n * 24);
        b.extend_from_slice(MAGIC);
        b.extend_from_slice(&VERSION.to_le_bytes());
        b.extend_from_slice(&self.steps.to_le_bytes());
        b.extend_from_slice(&self.time.to_le_bytes());
        b.extend_from_slice(&(n as u64).to_le_bytes());
        b.extend_from_slice(&(self.scene.len() as u64).to_le_bytes());
        b.extend_from_slice(self.scene.as_bytes());
        for a in &self.state {
            for v in a {
                b.extend_from_slice(&v.to_le_bytes());
            }
        }
        let h = fnv1a(&b);
        b.extend_from_slice(&h.to_le_bytes());
        b
    }

    /// Decodes a checkpoint, checking magic, version, lengths and hash.
    pub fn from_bytes(b: &[u8]) -> Result<Checkpoint> {
        let bad = |why: &str| WeftError::Scene(format!("not a valid weft checkpoint: {why}"));
        if b.len() < 8 + 4 + 8 + 8 + 8 + 8 + 8 || &b[..8] != MAGIC {
            return Err(bad("wrong magic or too short"));
        }
        let (body, tail) = b.split_at(b.len() - 8);
        if fnv1a(body) != u64::from_le_bytes(std::array::from_fn(|i| tail[i])) {
            return Err(bad("hash mismatch (truncated or corrupted file)"));
        }
        let mut r = Reader { body, at: 8 };
        let version = u32::from_le_bytes(r.array()?);
        if version != VERSION {
            return Err(bad(&format!("format version {version}, this weft reads {VERSION}")));
        }
        let steps = u64::from_le_bytes(r.array()?);
        let time = f64::from_le_bytes(r.array()?);
        let n = u64::from_le_bytes(r.array()?);
        let scene_len = u64::from_le_bytes(r.array()?);
        let scene_len = usize::try_from(scene_len).map_err(|_| bad("scene length"))?;
        let scene = String::from_utf8(r.bytes(scene_len)?.to_vec()).map_err(|_| bad("scene is not UTF-8"))?;
        let n = usize::try_from(n).map_err(|_| bad("particle count"))?;
        let header = 8 + 4 + 8 + 8 + 8 + 8 + scene_len;
        if n.checked_mul(24).is_none_or(|need| need != body.len().saturating_sub(header)) {
            return Err(bad("particle count does not match the file size"));
        }
        let mut state: [Vec<f32>; 6] = Default::default();
        for a in &mut state {
            let raw = r.bytes(n * 4)?;
            *a = raw.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        }
        Ok(Checkpoint { scene, steps, time, state })
    }

    /// Writes the checkpoint atomically.
    pub fn save(&self, path: &Path) -> Result<()> {
        write_atomic(path, &self.to_bytes())
    }

    /// Reads a checkpoint file (a regular file of at most [`crate::files::CHECKPOINT_LIMIT`] bytes).
    pub fn load(path: &Path) -> Result<Checkpoint> {
        let b = crate::files::read_limited(path, crate::files::CHECKPOINT_LIMIT, "checkpoint")?;
        Checkpoint::from_bytes(&b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;

    const SCENE: &str =
        "[effects]\ngravity = [0.0, -9.81, 0.0]\n[[cloth]]\nrows = 12\ncols = 9\nspacing = 0.05\npins = [\"first-row-corners\"]\n";

    #[test]
    fn resume_is_bitwise_identical_to_uninterrupted() {
        let scene = Scene::parse(SCENE, "s").unwrap();
        let mut a = scene.world().unwrap();
        for _ in 0..40 {
            a.step(1.0 / 60.0).unwrap();
        }
        let mut b = scene.world().unwrap();
        for _ in 0..17 {
            b.step(1.0 / 60.0).unwrap();
        }
        let bytes = b.checkpoint(SCENE).to_bytes();
        let c = Checkpoint::from_bytes(&bytes).unwrap();
        let mut r = Scene::parse(&c.scene, "s").unwrap().world().unwrap();
        r.restore(&c).unwrap();
        for _ in 17..40 {
            r.step(1.0 / 60.0).unwrap();
        }
        assert_eq!(r.steps(), 40);
        assert_eq!(a.checkpoint(SCENE), r.checkpoint(SCENE));
    }

    #[test]
    fn corrupt_files_are_errors() {
        let scene = Scene::parse(SCENE, "s").unwrap();
        let w = scene.world().unwrap();
        let mut bytes = w.checkpoint(SCENE).to_bytes();
        assert!(Checkpoint::from_bytes(&bytes[..bytes.len() - 3]).is_err());
        let k = bytes.len() / 2;
        bytes[k] ^= 0xff;
        assert!(Checkpoint::from_bytes(&bytes).unwrap_err().to_string().contains("hash"));
        assert!(Checkpoint::from_bytes(b"nonsense").is_err());
        assert!(Checkpoint::from_bytes(&[]).is_err());
    }
}
