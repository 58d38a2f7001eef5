//! Long-range attachments (tethers): one-sided distance limits from free particles to pins.
//!
//! Each free particle has at most one tether, to a pinned (inverse mass 0) anchor, so a single
//! pass is race-free: tethered particles are all distinct and anchors are only read. The
//! projection is `p <- anchor + (p - anchor) * L / |p - anchor|` when `|p - anchor| > L`.

use rayon::prelude::*;

use crate::data::lanes::{idx8, load, load_idx, round_up, F32s, SharedVec3, Vec3x8, LANES};
use crate::model::cloth::Tether;

/// Tethers in SoA, padded with dummies on the particle sink.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TetherSet {
    /// Tethered (free) particle.
    pub particle: Vec<u32>,
    /// Pinned anchor.
    pub anchor: Vec<u32>,
    /// Largest allowed distance, m.
    pub max_len: Vec<f32>,
    real: usize,
}

/// Tethers per parallel task.
const CHUNK: usize = 4096;

impl TetherSet {
    /// Lays out tethers (global indices); `sink` is an inert padding particle.
    pub fn new(tethers: &[Tether], sink: u32) -> Self {
        let len = round_up(tethers.len());
        let mut s = TetherSet {
            real: tethers.len(),
            ..Default::default()
        };
        s.particle = tethers.iter().map(|t| t.particle).collect();
        s.anchor = tethers.iter().map(|t| t.anchor).collect();
        s.max_len = tethers.iter().map(|t| t.max_len).collect();
        s.particle.resize(len, sink);
        s.anchor.resize(len, sink);
        s.max_len.resize(len, 0.0);
        s
    }

    /// Number of real tethers.
    pub fn len(&self) -> usize {
        self.real
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.real == 0
    }

    /// Projects every tether, SIMD, in parallel chunks when `parallel`.
    pub fn solve_simd(&self, px: &mut [f32], py: &mut [f32], pz: &mut [f32], parallel: bool) {
        let p = SharedVec3::new(px, py, pz);
        if parallel && self.particle.len() > CHUNK {
            self.particle
                .par_chunks(CHUNK)
                .zip(self.anchor.par_chunks(CHUNK))
                .zip(self.max_len.par_chunks(CHUNK))
                .for_each(|((i, a), l)| block_simd(i, a, l, &p));
        } else {
            block_simd(&self.particle, &self.anchor, &self.max_len, &p);
        }
    }

    /// Scalar twin of [`solve_simd`](Self::solve_simd).
    pub fn solve_scalar(&self, px: &mut [f32], py: &mut [f32], pz: &mut [f32]) {
        for k in 0..self.particle.len() {
            let (i, a) = (self.particle[k] as usize, self.anchor[k] as usize);
            let (dx, dy, dz) = (px[i] - px[a], py[i] - py[a], pz[i] - pz[a]);
            let len = (dx * dx + dy * dy + dz * dz).sqrt();
            let l = self.max_len[k];
            if len > l {
                let s = l / len;
                px[i] = px[a] + dx * s;
                py[i] = py[a] + dy * s;
                pz[i] = pz[a] + dz * s;
            }
        }
    }
}

/// Projects the tethers of one chunk, eight at a time. A block whose tethered particles are
/// consecutive (the usual layout: tethers listed in particle order) loads and stores them as
/// runs, and a block with one anchor reads it once; other blocks gather and scatter. A block
/// with no tether over its length writes nothing. Each lane's arithmetic is the scalar twin's,
/// so the choice of path changes no bit.
fn block_simd(particle: &[u32], anchor: &[u32], max_len: &[f32], p: &SharedVec3) {
    for k in (0..particle.len()).step_by(LANES) {
        let ii = load_idx(particle, k);
        let ia = load_idx(anchor, k);
        let i0 = ii[0];
        let run = ii == idx8(|l| i0.wrapping_add(l as u32));
        // SAFETY: indices are below the padded particle count (a run's last index is one of
        // them); tethered particles are distinct and never anchors, anchors are only read, so
        // no element is written by two tasks.
        let (pi, pa) = unsafe {
            let pi = if run { p.load_run(i0 as usize) } else { p.gather(&ii) };
            let pa = if ia == [ia[0]; LANES] {
                Vec3x8::splat(p.get(ia[0] as usize))
            } else {
                p.gather(&ia)
            };
            (pi, pa)
        };
        let d = pi - pa;
        let len = d.length_sq().sqrt();
        let l = load(max_len, k);
        let over = len.simd_gt(l);
        if !over.any() {
            continue;
        }
        let s = over.select(l / len, F32s::ONE);
        let out = Vec3x8::select(over, pa + d.scale(s), pi);
        // SAFETY: as above.
        unsafe {
            if run {
                p.store_run(i0 as usize, out);
            } else {
                p.scatter(&ii, out);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simd_matches_scalar_and_limits_length() {
        let n = 40;
        let len = round_up(n + 1);
        let mut x: Vec<f32> = (0..len).map(|i| (i as f32 * 0.37).sin() * 3.0).collect();
        let mut y: Vec<f32> = (0..len).map(|i| (i as f32 * 0.11).cos() * 3.0).collect();
        let mut z: Vec<f32> = (0..len).map(|i| i as f32 * 0.01).collect();
        let tethers: Vec<Tether> = (1..n as u32)
            .map(|i| Tether {
                particle: i,
                anchor: 0,
                max_len: 1.0 + (i % 3) as f32,
            })
            .collect();
        let set = TetherSet::new(&tethers, (len - 1) as u32);
        let (mut x2, mut y2, mut z2) = (x.clone(), y.clone(), z.clone());
        set.solve_scalar(&mut x, &mut y, &mut z);
        set.solve_simd(&mut x2, &mut y2, &mut z2, true);
        assert_eq!(x, x2);
        assert_eq!(y, y2);
        assert_eq!(z, z2);
        for t in &tethers {
            let i = t.particle as usize;
            let d = ((x[i] - x[0]).powi(2) + (y[i] - y[0]).powi(2) + (z[i] - z[0]).powi(2)).sqrt();
            assert!(d <= t.max_len * (1.0 + 1e-5), "{d} > {}", t.max_len);
        }
    }

    /// Every path of the lane kernel equals the scalar twin: blocks of consecutive particles
    /// with one anchor (runs, the anchor read once), consecutive particles whose anchors differ
    /// (alternating, or only the first lane's), particles out of order (gather and scatter),
    /// a block with no tether over its length (nothing written) and the padding.
    #[test]
    fn every_block_path_matches_scalar() {
        let n = 200usize;
        let len = round_up(n + 1);
        let mut tethers = Vec::new();
        // Runs from particle 2 on: tethers 0..8 slack, one block of anchor 0 alone, one whose
        // first lane alone takes anchor 1, then anchors 0 and 1 alternating.
        for i in 2..120u32 {
            let anchor = match i {
                26 => 1,
                40.. => i % 2,
                _ => 0,
            };
            let max_len = if i < 10 { 1e3 } else { 0.5 + (i % 5) as f32 * 0.3 };
            tethers.push(Tether {
                particle: i,
                anchor,
                max_len,
            });
        }
        // Out of order: descending indices.
        for i in (120..n as u32).rev() {
            tethers.push(Tether {
                particle: i,
                anchor: 1,
                max_len: 0.8,
            });
        }
        let set = TetherSet::new(&tethers, (len - 1) as u32);
        let start: [Vec<f32>; 3] = std::array::from_fn(|a| (0..len).map(|i| ((i * (a + 3)) as f32 * 0.29).sin() * 4.0).collect());
        let mut want = start.clone();
        let [wx, wy, wz] = &mut want;
        set.solve_scalar(wx, wy, wz);
        let moved = (0..n).filter(|&i| (0..3).any(|a| want[a][i] != start[a][i])).count();
        assert!(moved > 100, "{moved} particles moved");
        assert!((2..10).all(|i| (0..3).all(|a| want[a][i] == start[a][i])), "the slack block stays");
        for parallel in [false, true] {
            let mut got = start.clone();
            let [gx, gy, gz] = &mut got;
            set.solve_simd(gx, gy, gz, parallel);
            assert_eq!(got, want, "parallel {parallel}");
        }
    }
}
