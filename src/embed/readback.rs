//! Reading positions and vertex normals into the caller's buffers.
//!
//! The host gives a buffer in its own layout: `[[f32; 3]]`, flat interleaved `[f32]`
//! (`x0 y0 z0 x1 ...`), `mint` points or vectors, or three separate slices ([`Soa`]). The
//! length is checked (one entry per particle, or `3 n` floats for a flat buffer) and the values
//! are written straight into it: no temporary copy, no allocation.
//!
//! Vertex normals are area weighted: each triangle `(a, b, c)` adds its unnormalised normal
//! `(x_b - x_a) × (x_c - x_a)` (twice its area times its unit normal) to its three corners, in
//! triangle order, and each sum is then normalised. The output buffer itself is the
//! accumulator. A particle in no triangle, or only in degenerate ones, gets the zero vector.
//! Triangles wind counter-clockwise seen from `u × v` of their [`ClothDesc`](crate::ClothDesc),
//! so normals point along `u × v`.

use crate::error::{Result, WeftError};
use crate::world::World;

/// A caller's buffer of 3-vectors that weft writes into.
pub trait Vec3Out {
    /// Number of 3-vectors the buffer holds, or an error if its length is not valid for `n`.
    fn check_len(&self, name: &'static str, n: usize) -> Result<()>;
    /// Writes vector `i`.
    fn put(&mut self, i: usize, v: [f32; 3]);
    /// Reads vector `i` back (used to accumulate normals in place).
    fn get(&self, i: usize) -> [f32; 3];
}

fn expect(name: &'static str, got: usize, expected: usize) -> Result<()> {
    if got == expected {
        Ok(())
    } else {
        Err(WeftError::BufferLength { name, got, expected })
    }
}

impl Vec3Out for [[f32; 3]] {
    fn check_len(&self, name: &'static str, n: usize) -> Result<()> {
        expect(name, self.len(), n)
    }
    fn put(&mut self, i: usize, v: [f32; 3]) {
        self[i] = v;
    }
    fn get(&self, i: usize) -> [f32; 3] {
        self[i]
    }
}

/// Flat interleaved floats: `x0 y0 z0 x1 y1 z1 ...`, length `3 n`.
impl Vec3Out for [f32] {
    fn check_len(&self, name: &'static str, n: usize) -> Result<()> {
        expect(name, self.len(), n.saturating_mul(3))
    }
    fn put(&mut self, i: usize, v: [f32; 3]) {
        self[3 * i..3 * i + 3].copy_from_slice(&v);
    }
    fn get(&self, i: usize) -> [f32; 3] {
        [self[3 * i], self[3 * i + 1], self[3 * i + 2]]
    }
}

impl Vec3Out for [mint::Point3<f32>] {
    fn check_len(&self, name: &'static str, n: usize) -> Result<()> {
        expect(name, self.len(), n)
    }
    fn put(&mut self, i: usize, v: [f32; 3]) {
        self[i] = v.into();
    }
    fn get(&self, i: usize) -> [f32; 3] {
        self[i].into()
    }
}

impl Vec3Out for [mint::Vector3<f32>] {
    fn check_len(&self, name: &'static str, n: usize) -> Result<()> {
        expect(name, self.len(), n)
    }
    fn put(&mut self, i: usize, v: [f32; 3]) {
        self[i] = v.into();
    }
    fn get(&self, i: usize) -> [f32; 3] {
        self[i].into()
    }
}

/// Three separate output slices (structure of arrays), each of length `n`.
pub struct Soa<'a> {
    /// x components.
    pub x: &'a mut [f32],
    /// y components.
    pub y: &'a mut [f32],
    /// z components.
    pub z: &'a mut [f32],
}

impl Vec3Out for Soa<'_> {
    fn check_len(&self, name: &'static str, n: usize) -> Result<()> {
        expect(name, self.x.len(), n)?;
        expect(name, self.y.len(), n)?;
        expect(name, self.z.len(), n)
    }
    fn put(&mut self, i: usize, v: [f32; 3]) {
        (self.x[i], self.y[i], self.z[i]) = (v[0], v[1], v[2]);
    }
    fn get(&self, i: usize) -> [f32; 3] {
        [self.x[i], self.y[i], self.z[i]]
    }
}

impl World {
    /// Copies the positions of all real particles into `out` (any [`Vec3Out`] layout).
    pub fn read_positions<O: Vec3Out + ?Sized>(&self, out: &mut O) -> Result<()> {
        let n = self.particles.count();
        out.check_len("positions", n)?;
        for i in 0..n {
            out.put(i, self.particles.position(i));
        }
        Ok(())
    }

    /// Writes area-weighted unit vertex normals of all real particles into `out` (see the
    /// module docs; zero for a particle in no non-degenerate triangle).
    pub fn read_normals<O: Vec3Out + ?Sized>(&self, out: &mut O) -> Result<()> {
        let n = self.particles.count();
        out.check_len("normals", n)?;
        for i in 0..n {
            out.put(i, [0.0; 3]);
        }
        let p = &self.particles;
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| i as usize);
            let e1 = [p.x[b] - p.x[a], p.y[b] - p.y[a], p.z[b] - p.z[a]];
            let e2 = [p.x[c] - p.x[a], p.y[c] - p.y[a], p.z[c] - p.z[a]];
            let m = [
                e1[1] * e2[2] - e1[2] * e2[1],
                e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0],
            ];
            for k in [a, b, c] {
                let s = out.get(k);
                out.put(k, [s[0] + m[0], s[1] + m[1], s[2] + m[2]]);
            }
        }
        for i in 0..n {
            let s = out.get(i);
            let l = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
            let v = if l > 0.0 && l.is_finite() {
                [s[0] / l, s[1] / l, s[2] / l]
            } else {
                [0.0; 3]
            };
            out.put(i, v);
        }
        Ok(())
    }

    /// Positions for display between the last two steps taken by [`advance`](World::advance):
    /// `x_prev + alpha (x - x_prev)`, `alpha` in `[0, 1]` (usually
    /// [`AdvanceReport::alpha`](crate::embed::AdvanceReport::alpha)). If the last step was not
    /// taken by `advance` (or none was), the current positions are written.
    pub fn interpolated_positions<O: Vec3Out + ?Sized>(&self, alpha: f32, out: &mut O) -> Result<()> {
        if !(0.0..=1.0).contains(&alpha) {
            return Err(WeftError::param("alpha", alpha, "must be between 0 and 1"));
        }
        let n = self.particles.count();
        out.check_len("interpolated positions", n)?;
        if self.embed.prev_steps.map(|s| s + 1) != Some(self.steps) {
            return self.read_positions(out);
        }
        let [px, py, pz] = &self.embed.prev;
        let p = &self.particles;
        for i in 0..n {
            out.put(
                i,
                [
                    px[i] + alpha * (p.x[i] - px[i]),
                    py[i] + alpha * (p.y[i] - py[i]),
                    pz[i] + alpha * (p.z[i] - pz[i]),
                ],
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ClothDesc, Effects, PinSpec, SolverParams};

    fn flat_world() -> World {
        let mut w = World::new(SolverParams::default(), Effects::default()).unwrap();
        w.add_cloth(&ClothDesc {
            rows: 4,
            cols: 3,
            spacing: 0.1,
            pins: vec![PinSpec::FirstRowCorners],
            ..Default::default()
        })
        .unwrap();
        w
    }

    #[test]
    fn every_layout_gets_the_same_positions() {
        let w = flat_world();
        let n = w.particle_count();
        let mut a = vec![[0.0f32; 3]; n];
        let mut f = vec![0.0f32; 3 * n];
        let mut m = vec![mint::Point3 { x: 0.0, y: 0.0, z: 0.0 }; n];
        let (mut x, mut y, mut z) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        w.read_positions(&mut a[..]).unwrap();
        w.read_positions(&mut f[..]).unwrap();
        w.read_positions(&mut m[..]).unwrap();
        w.read_positions(&mut Soa {
            x: &mut x,
            y: &mut y,
            z: &mut z,
        })
        .unwrap();
        let [sx, sy, sz] = w.positions();
        for i in 0..n {
            let e = [sx[i], sy[i], sz[i]];
            assert_eq!(a[i], e);
            assert_eq!(&f[3 * i..3 * i + 3], &e);
            assert_eq!(<[f32; 3]>::from(m[i]), e);
            assert_eq!([x[i], y[i], z[i]], e);
        }
    }

    #[test]
    fn wrong_lengths_are_errors() {
        let w = flat_world();
        let n = w.particle_count();
        assert!(w.read_positions(&mut vec![[0.0f32; 3]; n - 1][..]).is_err());
        assert!(w.read_positions(&mut vec![0.0f32; 3 * n + 1][..]).is_err());
        assert!(w.read_normals(&mut vec![0.0f32; n][..]).is_err());
        let (mut x, mut y, mut z) = (vec![0.0; n], vec![0.0; n - 1], vec![0.0; n]);
        let e = w
            .read_positions(&mut Soa {
                x: &mut x,
                y: &mut y,
                z: &mut z,
            })
            .unwrap_err();
        assert!(matches!(e, WeftError::BufferLength { got, expected, .. } if got == n - 1 && expected == n));
        assert!(w.interpolated_positions(1.5, &mut vec![[0.0f32; 3]; n][..]).is_err());
    }

    #[test]
    fn flat_cloth_normals_are_u_cross_v() {
        // Default u = +x, v = -y: u × v = -z for every particle.
        let w = flat_world();
        let mut nrm = vec![[9.0f32; 3]; w.particle_count()];
        w.read_normals(&mut nrm[..]).unwrap();
        for v in nrm {
            assert_eq!(v, [0.0, 0.0, -1.0]);
        }
    }

    #[test]
    fn normals_weight_by_area() {
        // Two triangles meeting at particle 0: a big one facing +z and a small one facing +x.
        let mut w = World::new(SolverParams::default(), Effects::default()).unwrap();
        w.particles
            .extend(&[[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 1.0]], &[1.0; 4]);
        w.triangles = vec![[0, 1, 2], [0, 2, 3]];
        let mut nrm = [[0.0f32; 3]; 4];
        w.read_normals(&mut nrm[..]).unwrap();
        // Sum of (0,0,4) and (2,0,0): direction (1, 0, 2) / sqrt(5).
        let s = 5.0f32.sqrt();
        assert!(
            (nrm[0][0] - 1.0 / s).abs() < 1e-6 && (nrm[0][2] - 2.0 / s).abs() < 1e-6,
            "{:?}",
            nrm[0]
        );
        assert_eq!(nrm[1], [0.0, 0.0, 1.0]);
        assert_eq!(nrm[3], [1.0, 0.0, 0.0]);
    }
}
