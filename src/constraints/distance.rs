//! XPBD distance constraints in coloured SoA batches: the SIMD kernel and its scalar twin.
//!
//! Each colour stores `a, b, rest, compliance, lambda` as separate arrays padded to the lane
//! width with dummy constraints on the particle sink (inverse mass 0, so they move nothing).
//! Padding sits only at the end of a colour, so only the last parallel chunk touches the sink.
//! The SIMD kernel and the scalar twin perform the same operations in the same order without
//! fused multiply-add, so they agree bit for bit; within a colour no particle repeats, so the
//! order of constraints (and therefore chunking and thread count) cannot change the result.

use rayon::prelude::*;

use crate::constraints::colour::colour_pairs;
use crate::lanes::{gather1, load, load_idx, round_up, store, F32s, SharedVec3, LANES};

/// Below this length a constraint has no direction and is skipped for the substep.
pub const MIN_LENGTH: f32 = 1e-9;

/// Constraints per parallel task (a multiple of the lane width).
pub const CHUNK: usize = 2048;

/// One colour: constraints that share no particle.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Colour {
    /// First particle of each constraint.
    pub a: Vec<u32>,
    /// Second particle.
    pub b: Vec<u32>,
    /// Rest length, m.
    pub rest: Vec<f32>,
    /// Compliance, m/N.
    pub compliance: Vec<f32>,
    /// Accumulated Lagrange multiplier of the current substep.
    pub lambda: Vec<f32>,
    /// Number of real (non-padding) constraints.
    pub real: usize,
}

/// All distance constraints of a world, grouped by colour.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DistanceSet {
    /// The colours, solved in order.
    pub colours: Vec<Colour>,
}

/// A distance constraint given to [`DistanceSet::new`] (global particle indices).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistanceInput {
    /// First particle.
    pub a: u32,
    /// Second particle.
    pub b: u32,
    /// Rest length, m.
    pub rest: f32,
    /// Compliance, m/N.
    pub compliance: f32,
}

impl DistanceSet {
    /// Colours the constraints and lays them out; `sink` is an inert padding particle.
    pub fn new(input: &[DistanceInput], particle_count: usize, sink: u32) -> Self {
        let pairs: Vec<(u32, u32)> = input.iter().map(|c| (c.a, c.b)).collect();
        let (colour_of, count) = colour_pairs(&pairs, particle_count);
        let mut colours = vec![Colour::default(); count as usize];
        for (c, &k) in input.iter().zip(&colour_of) {
            let col = &mut colours[k as usize];
            col.a.push(c.a);
            col.b.push(c.b);
            col.rest.push(c.rest);
            col.compliance.push(c.compliance);
        }
        for col in &mut colours {
            col.real = col.a.len();
            let len = round_up(col.real);
            col.a.resize(len, sink);
            col.b.resize(len, sink);
            col.rest.resize(len, 0.0);
            col.compliance.resize(len, 0.0);
            col.lambda = vec![0.0; len];
        }
        colours.retain(|c| c.real > 0);
        DistanceSet { colours }
    }

    /// Number of real constraints.
    pub fn len(&self) -> usize {
        self.colours.iter().map(|c| c.real).sum()
    }

    /// Whether there are no constraints.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Sets every multiplier to zero (start of a substep).
    pub fn reset_lambda(&mut self) {
        for c in &mut self.colours {
            c.lambda.fill(0.0);
        }
    }

    /// One Gauss–Seidel sweep over all colours, SIMD, each colour in parallel chunks when
    /// `parallel` (on the current rayon pool).
    pub fn solve_simd(&mut self, px: &mut [f32], py: &mut [f32], pz: &mut [f32], w: &[f32], inv_h2: f32, parallel: bool) {
        let p = SharedVec3::new(px, py, pz);
        for col in &mut self.colours {
            if parallel && col.a.len() > CHUNK {
                col.a
                    .par_chunks(CHUNK)
                    .zip(col.b.par_chunks(CHUNK))
                    .zip(col.rest.par_chunks(CHUNK))
                    .zip(col.compliance.par_chunks(CHUNK))
                    .zip(col.lambda.par_chunks_mut(CHUNK))
                    .for_each(|((((a, b), rest), comp), lambda)| solve_block_simd(a, b, rest, comp, lambda, &p, w, inv_h2));
            } else {
                solve_block_simd(&col.a, &col.b, &col.rest, &col.compliance, &mut col.lambda, &p, w, inv_h2);
            }
        }
    }

    /// The scalar f32 twin of [`solve_simd`](Self::solve_simd): one constraint at a time,
    /// one thread, the same arithmetic.
    pub fn solve_scalar(&mut self, px: &mut [f32], py: &mut [f32], pz: &mut [f32], w: &[f32], inv_h2: f32) {
        for col in &mut self.colours {
            for k in 0..col.a.len() {
                let (a, b) = (col.a[k] as usize, col.b[k] as usize);
                let (wa, wb) = (w[a], w[b]);
                let (dx, dy, dz) = (px[b] - px[a], py[b] - py[a], pz[b] - pz[a]);
                let len = (dx * dx + dy * dy + dz * dz).sqrt();
                let c = len - col.rest[k];
                let alpha = col.compliance[k] * inv_h2;
                let denom = wa + wb + alpha;
                let valid = len > MIN_LENGTH && denom > 0.0;
                let dl = if valid { (-c - alpha * col.lambda[k]) / denom } else { 0.0 };
                let s = if valid { dl / len } else { 0.0 };
                let (sa, sb) = (wa * s, wb * s);
                px[a] -= dx * sa;
                py[a] -= dy * sa;
                pz[a] -= dz * sa;
                px[b] += dx * sb;
                py[b] += dy * sb;
                pz[b] += dz * sb;
                col.lambda[k] += dl;
            }
        }
    }
}

#[allow(clippy::too_many_arguments)]
#[inline]
fn solve_block_simd(a: &[u32], b: &[u32], rest: &[f32], comp: &[f32], lambda: &mut [f32], p: &SharedVec3, w: &[f32], inv_h2: f32) {
    let inv_h2 = F32s::splat(inv_h2);
    let zero = F32s::ZERO;
    let min_len = F32s::splat(MIN_LENGTH);
    for i in (0..a.len()).step_by(LANES) {
        let ia = load_idx(a, i);
        let ib = load_idx(b, i);
        // SAFETY: indices were built below the padded particle count, and within one colour no
        // particle appears in two constraints, so no other task touches these elements.
        let (pa, pb) = unsafe { (p.gather(&ia), p.gather(&ib)) };
        let wa = gather1(w, &ia);
        let wb = gather1(w, &ib);
        let d = pb - pa;
        let len = d.length_sq().sqrt();
        let c = len - load(rest, i);
        let alpha = load(comp, i) * inv_h2;
        let denom = wa + wb + alpha;
        let lam = load(lambda, i);
        let valid = len.simd_gt(min_len) & denom.simd_gt(zero);
        let dl = valid.select((-c - alpha * lam) / denom, zero);
        let s = valid.select(dl / len, zero);
        let pa = pa - d.scale(wa * s);
        let pb = pb + d.scale(wb * s);
        store(lambda, i, lam + dl);
        // SAFETY: as above; `a` is scattered before `b`, and `a != b` for real constraints.
        unsafe {
            p.scatter(&ia, pa);
            p.scatter(&ib, pb);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn random_set(n: usize, m: usize, seed: u64) -> (Vec<DistanceInput>, Vec<f32>, [Vec<f32>; 3]) {
        let mut rnd = crate::test_rng::unit(seed);
        let len = round_up(n + 1);
        let mut pos = [vec![0.0; len], vec![0.0; len], vec![0.0; len]];
        let mut w = vec![0.0; len];
        for i in 0..n {
            for p in pos.iter_mut() {
                p[i] = rnd() * 2.0 - 1.0;
            }
            w[i] = if rnd() < 0.1 { 0.0 } else { 0.1 + rnd() * 10.0 };
        }
        let mut cons = Vec::new();
        for _ in 0..m {
            let a = (rnd() * n as f32) as u32 % n as u32;
            let b = (rnd() * n as f32) as u32 % n as u32;
            if a != b {
                cons.push(DistanceInput {
                    a,
                    b,
                    rest: rnd(),
                    compliance: if rnd() < 0.3 { 0.0 } else { rnd() * 1e-3 },
                });
            }
        }
        (cons, w, pos)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// The SIMD kernel (serial and parallel) equals the scalar twin bit for bit.
        #[test]
        fn simd_matches_scalar_bitwise(n in 2usize..300, m in 0usize..2000, seed in 1u64..u64::MAX, inv_h2 in 1.0f32..1e6) {
            let (cons, w, pos) = random_set(n, m, seed);
            let set = DistanceSet::new(&cons, n, (round_up(n + 1) - 1) as u32);
            let mut s = (set.clone(), pos.clone());
            let mut v = (set.clone(), pos.clone());
            let mut par = (set, pos);
            for _ in 0..3 {
                let [x, y, z] = &mut s.1;
                s.0.solve_scalar(x, y, z, &w, inv_h2);
                let [x, y, z] = &mut v.1;
                v.0.solve_simd(x, y, z, &w, inv_h2, false);
                let [x, y, z] = &mut par.1;
                par.0.solve_simd(x, y, z, &w, inv_h2, true);
            }
            for k in 0..3 {
                let bits = |a: &Vec<f32>| a.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
                prop_assert_eq!(bits(&s.1[k]), bits(&v.1[k]));
                prop_assert_eq!(bits(&s.1[k]), bits(&par.1[k]));
            }
        }
    }

    #[test]
    fn rigid_constraint_converges_to_rest_length() {
        let cons = [DistanceInput {
            a: 0,
            b: 1,
            rest: 1.0,
            compliance: 0.0,
        }];
        let set = DistanceSet::new(&cons, 2, 7);
        let mut s = set.clone();
        let mut x = vec![0.0; 8];
        let mut y = vec![0.0; 8];
        let mut z = vec![0.0; 8];
        x[1] = 3.0;
        let w = [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        s.solve_simd(&mut x, &mut y, &mut z, &w, 1.0, false);
        assert!((x[1] - x[0] - 1.0).abs() < 1e-6);
        assert!((x[0] - 1.0).abs() < 1e-6, "equal masses move equally: {}", x[0]);
    }

    #[test]
    fn coincident_particles_stay_finite() {
        let cons = [DistanceInput {
            a: 0,
            b: 1,
            rest: 1.0,
            compliance: 0.0,
        }];
        let mut s = DistanceSet::new(&cons, 2, 7);
        let (mut x, mut y, mut z) = (vec![0.5; 8], vec![0.5; 8], vec![0.5; 8]);
        let w = [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        s.solve_simd(&mut x, &mut y, &mut z, &w, 1.0, false);
        assert!(x.iter().chain(&y).chain(&z).all(|v| v.is_finite()));
    }
}
