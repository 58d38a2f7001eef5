//! Each particle's travel for a step (the first bullet of the pipeline in
//! [`crate::self_collision`]): its speed relative to the mean velocity of the free particles,
//! or the mean's own speed if larger, over the step, times [`TRAVEL_GROWTH`], at least
//! [`TRAVEL_FLOOR`] and at most the bound (the bound for a non-finite velocity). Beside the
//! travels, a [`Tally`]: the smallest and largest travel and a histogram of them, from which
//! the hash sizes its cells for all but the fastest particles.
//!
//! Eight particles at a time when the lanes are on, each lane doing the scalar twin's
//! operations in its order (no fused multiply-add), so both give the same bits; in parallel
//! over fixed chunks of [`TRAVEL_CHUNK`] particles when the step is. The chunks' tallies are
//! combined by minimum, maximum and integer counts, which are exact in any order, so nothing
//! depends on the number of threads.

use rayon::prelude::*;

use crate::data::exec::Exec;
use crate::data::lanes::{load, store, F32s, LANES};
use crate::model::self_collision::{TRAVEL_FLOOR, TRAVEL_GROWTH};

/// Bins of the travels between the floor and the bound.
const TRAVEL_BINS: usize = 16;

/// Particles one parallel task handles.
const TRAVEL_CHUNK: usize = 4096;

/// The step's constants of the travel.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TravelRule {
    /// Mean velocity of the free particles.
    pub m: [f32; 3],
    /// The step, s, and the collision distance, m.
    pub dt: f32,
    pub d: f32,
    /// The bound: the setting's travel over `d`.
    pub bound: f32,
}

/// The smallest and largest travel of some particles, and how many have a travel of at most
/// `floor + k (bound - floor) / TRAVEL_BINS`, by the smallest such `k` (`floor` the smaller of
/// [`TRAVEL_FLOOR`] and the bound).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Tally {
    pub lo: f32,
    pub hi: f32,
    pub bins: [usize; TRAVEL_BINS + 1],
}

impl TravelRule {
    /// The smallest travel: [`TRAVEL_FLOOR`], or the bound if lower.
    fn floor(&self) -> f32 {
        TRAVEL_FLOOR.min(self.bound)
    }

    /// The width of a bin of the histogram.
    fn width(&self) -> f32 {
        (self.bound - self.floor()) / TRAVEL_BINS as f32
    }

    /// The largest travel of the hash cells' members, from the `tally` of `n` particles: the
    /// upper edge of the first bin by which at most `fast` particles are left faster (the
    /// bound past the last bin), at most the largest travel.
    pub(crate) fn members_travel(&self, tally: &Tally, n: usize, fast: usize) -> f32 {
        let mut slower = 0;
        let k = tally.bins.iter().position(|&c| {
            slower += c;
            n - slower <= fast
        });
        let edge = k.map_or(self.bound, |k| {
            if k == TRAVEL_BINS {
                self.bound
            } else {
                self.floor() + k as f32 * self.width()
            }
        });
        edge.min(tally.hi)
    }

    /// The tally of no particle.
    fn empty(&self) -> Tally {
        Tally {
            lo: self.bound,
            hi: self.floor(),
            bins: [0; TRAVEL_BINS + 1],
        }
    }

    /// The travels `t` of the particles with velocities `v` (`t`, `v` of one length) and their
    /// tally: eight at a time when `simd`, else one by one (the twin; the same bits).
    pub(crate) fn chunk(&self, v: [&[f32]; 3], t: &mut [f32], simd: bool) -> Tally {
        let mut tally = self.empty();
        let len = t.len().min(v[0].len()).min(v[1].len()).min(v[2].len());
        let (floor, width, bound) = (self.floor(), self.width(), self.bound);
        let m2 = self.m2();
        let mut done = 0;
        if simd {
            let m = self.m.map(F32s::splat);
            let (m2v, dt, d) = (F32s::splat(m2), F32s::splat(self.dt), F32s::splat(self.d));
            let (growth, least, most) = (F32s::splat(TRAVEL_GROWTH), F32s::splat(TRAVEL_FLOOR), F32s::splat(bound));
            let (floorv, widthv, top) = (F32s::splat(floor), F32s::splat(width), F32s::splat(TRAVEL_BINS as f32));
            let (mut lo, mut hi) = (most, F32s::splat(floor));
            let mut lanes = [[0usize; TRAVEL_BINS + 1]; LANES];
            done = len / LANES * LANES;
            for i in (0..done).step_by(LANES) {
                let u = [load(v[0], i) - m[0], load(v[1], i) - m[1], load(v[2], i) - m[2]];
                let u2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
                let u2 = u2.is_nan().select(u2, u2.max(m2v));
                let rel = u2.sqrt() * dt / d;
                let tv = rel.is_finite().select((growth * rel).max(least).min(most), most);
                store(t, i, tv);
                (lo, hi) = (lo.min(tv), hi.max(tv));
                let k = if width > 0.0 {
                    ((tv - floorv) / widthv).ceil().max(F32s::ZERO).min(top)
                } else {
                    F32s::ZERO
                };
                for (l, k) in k.to_array().into_iter().enumerate() {
                    lanes[l][k as usize] += 1;
                }
            }
            let (lo, hi) = (lo.to_array(), hi.to_array());
            for ((lo, hi), lane) in lo.into_iter().zip(hi).zip(lanes) {
                tally.lo = tally.lo.min(lo);
                tally.hi = tally.hi.max(hi);
                for (b, c) in tally.bins.iter_mut().zip(lane) {
                    *b += c;
                }
            }
        }
        for i in done..len {
            let u = [v[0][i] - self.m[0], v[1][i] - self.m[1], v[2][i] - self.m[2]];
            let u2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
            let u2 = if u2.is_nan() { u2 } else { u2.max(m2) };
            let rel = u2.sqrt() * self.dt / self.d;
            let ti = if rel.is_finite() {
                (TRAVEL_GROWTH * rel).max(TRAVEL_FLOOR).min(bound)
            } else {
                bound
            };
            t[i] = ti;
            tally.count(ti, floor, width);
        }
        tally
    }

    /// The squared length of the mean velocity (a particle stopped by an obstacle moves at
    /// minus the mean relative to it).
    fn m2(&self) -> f32 {
        let m = self.m;
        m[0] * m[0] + m[1] * m[1] + m[2] * m[2]
    }

    /// The travels `t` of the first `t.len()` particles of `v` and their tally, in parallel
    /// over fixed chunks when `exec` is parallel, with its lanes (the same bits either way).
    pub(crate) fn all(&self, v: [&[f32]; 3], t: &mut [f32], exec: Exec) -> Tally {
        let n = t.len();
        let v = v.map(|a| &a[..n.min(a.len())]);
        if !(exec.parallel() && n > TRAVEL_CHUNK) {
            return self.chunk(v, t, exec.simd());
        }
        t.par_chunks_mut(TRAVEL_CHUNK)
            .enumerate()
            .map(|(c, t)| {
                let s = c * TRAVEL_CHUNK;
                let part = v.map(|a| &a[s.min(a.len())..(s + t.len()).min(a.len())]);
                self.chunk(part, t, exec.simd())
            })
            .reduce(|| self.empty(), |a, b| a.join(&b))
    }
}

impl Tally {
    /// Counts one travel `t` (the scalar form of the lanes' binning; `floor` and `width` those
    /// of the rule).
    #[inline]
    fn count(&mut self, t: f32, floor: f32, width: f32) {
        (self.lo, self.hi) = (self.lo.min(t), self.hi.max(t));
        let k = if width > 0.0 { ((t - floor) / width).ceil() } else { 0.0 };
        self.bins[(k.max(0.0) as usize).min(TRAVEL_BINS)] += 1;
    }

    /// The tally of two sets of particles together.
    fn join(&self, other: &Tally) -> Tally {
        let mut bins = self.bins;
        for (b, c) in bins.iter_mut().zip(other.bins) {
            *b += c;
        }
        Tally {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
            bins,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::self_collision::{SelfCollision, SelfCollisionData};
    use crate::test_rng::signed;

    /// The lanes, the scalar twin and the parallel chunks give the same travels and tallies,
    /// with fast, slow, pinned-still and non-finite velocities, a zero-width histogram (bound
    /// at the floor) and lengths that leave a tail.
    #[test]
    fn lanes_twin_and_chunks_agree() {
        let mut rng = signed(21);
        let n = 3 * TRAVEL_CHUNK + 13;
        let mut v: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| rng()).collect());
        for (k, i) in [5usize, 70, 4100, 9000].into_iter().enumerate() {
            v[k % 3][i] = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e30][k];
        }
        for i in (0..n).step_by(17) {
            for a in &mut v {
                a[i] *= 40.0;
            }
        }
        for i in (3..n).step_by(29) {
            for a in &mut v {
                a[i] = 0.0;
            }
        }
        let vs = [&v[0][..], &v[1][..], &v[2][..]];
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        for (m, bound) in [
            ([0.1f32, -0.3, 0.05], 1.0f32),
            ([0.0; 3], 0.5),
            ([2.0, 0.0, 0.0], 0.25),
            ([0.0; 3], 0.1),
        ] {
            let rule = TravelRule {
                m,
                dt: 0.016,
                d: 0.01,
                bound,
            };
            let mut want = vec![0.0f32; n];
            let tally = rule.chunk(vs, &mut want, false);
            assert_eq!(tally.bins.iter().sum::<usize>(), n);
            assert!(tally.lo < tally.hi || bound <= TRAVEL_FLOOR, "{bound}: {tally:?}");
            assert!(want.iter().all(|t| t.is_finite() && *t <= bound && *t >= TRAVEL_FLOOR.min(bound)));
            let bits = |t: &[f32]| t.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            for len in [n, n - 5, 8, 3] {
                let mut got = vec![0.0f32; len];
                let part = vs.map(|a| &a[..len]);
                let t = rule.chunk(part, &mut got, true);
                let mut twin = vec![0.0f32; len];
                assert_eq!(t, rule.chunk(part, &mut twin, false), "lanes, {len}");
                assert_eq!(bits(&got), bits(&twin), "lanes, {len}");
            }
            for exec in [Exec::new(true, true), Exec::new(true, false), Exec::new(false, true)] {
                let mut got = vec![0.0f32; n];
                let t = pool.install(|| rule.all(vs, &mut got, exec));
                assert_eq!(t, tally, "{exec:?}");
                assert_eq!(bits(&got), bits(&want), "{exec:?}");
            }
        }
    }

    /// The cells' members: all but at most `fast` of the fastest. Three fast particles of a
    /// hundred leave the members at the floor, five at the bound; the upper edge of a middle
    /// bin when only two are faster than it; never above the largest travel.
    #[test]
    fn members_travel_leaves_out_at_most_the_fast_ones() {
        let rule = TravelRule {
            m: [0.0; 3],
            dt: 0.01,
            d: 0.01,
            bound: 1.0,
        };
        let members = |fast: &[f32]| {
            let t: Vec<f32> = (0..100).map(|i| fast.get(i).copied().unwrap_or(TRAVEL_FLOOR)).collect();
            let mut tally = rule.empty();
            for &x in &t {
                tally.count(x, rule.floor(), rule.width());
            }
            rule.members_travel(&tally, 100, 3)
        };
        assert_eq!(members(&[1.0; 3]), TRAVEL_FLOOR);
        assert_eq!(members(&[1.0; 5]), 1.0);
        let (edge, inside) = (TRAVEL_FLOOR + 8.0 * rule.width(), TRAVEL_FLOOR + 7.5 * rule.width());
        assert_eq!(members(&[1.0, 1.0, inside, inside, inside]), edge);
        assert_eq!(members(&[inside; 5]), inside, "capped at the largest travel");
        assert_eq!(members(&[]), TRAVEL_FLOOR);
    }

    /// The particles' travels: the floor at rest; `TRAVEL_GROWTH` times the speed relative to
    /// the free particles' mean over a step, or the mean's speed if larger (a pinned particle at
    /// rest while the others fall); the setting's bound for fast or non-finite velocities, each
    /// particle its own; and the query reach follows the largest while the rest-neighbour radius
    /// keeps the setting's.
    #[test]
    fn step_travel_follows_the_velocities() {
        let mut data = SelfCollisionData::default();
        let rest: Vec<[f32; 3]> = (0..16).map(|i| [(i % 4) as f32 * 0.01, 0.0, (i / 4) as f32 * 0.01]).collect();
        data.add_cloth(&rest, 0, 0.01, 0.01);
        data.config = Some(SelfCollision::default());
        let n = 16;
        let d = data.distance();
        let mut w = vec![1.0f32; n];
        w[0] = 0.0;
        let travel = |data: &mut SelfCollisionData, vy: &[f32], dt: f32| {
            let zero = vec![0.0f32; n];
            data.adapt_travel([&zero, vy, &zero], &w, n, dt, Exec::Parallel);
            data.step_travel().unwrap()
        };
        assert_eq!(data.step_travel(), None);
        assert_eq!(travel(&mut data, &[0.0; 16], 0.01), TRAVEL_FLOOR);
        // The free particles fall at 1 m/s, the pinned one stays: u = 1 m/s.
        let mut vy = vec![-1.0f32; n];
        vy[0] = 0.0;
        let t = travel(&mut data, &vy, 0.004);
        assert!((t - TRAVEL_GROWTH * 0.004 / d).abs() < 1e-5, "{t}");
        assert!(data.step_travels(n).iter().all(|&e| e == t));
        let a = data.active().unwrap();
        assert_eq!(a.travel, t);
        assert_eq!(a.q, d + (t + t) * d);
        assert_eq!(a.skip, SelfCollision::default().rest_skip_factor() * d);
        assert_eq!(travel(&mut data, &vy, 1.0), SelfCollision::default().travel);
        // One fast particle: its own travel is the bound, the others keep theirs (the mean's
        // speed, 5/3 m/s, above theirs relative to it).
        vy[3] = -11.0;
        assert_eq!(travel(&mut data, &vy, 0.002), SelfCollision::default().travel);
        let each = data.step_travels(n).to_vec();
        assert!(each[3] == 1.0 && each[4] < 1.0 && each[4] > TRAVEL_FLOOR, "{each:?}");
        vy[5] = f32::NAN;
        assert_eq!(travel(&mut data, &vy, 0.004), SelfCollision::default().travel);
        assert_eq!(data.step_travels(n)[5], 1.0);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        /// On random velocities (a share of them scaled up past the bound, set to zero, or
        /// replaced by non-finite, huge, signed-zero or subnormal values), random mean
        /// velocities, steps and bounds, the lanes give every particle the scalar twin's travel
        /// bit for bit and the same tally, for any length; the parallel chunks on two threads
        /// give the serial result.
        #[test]
        fn travel_lanes_and_chunks_equal_the_scalar_twin(
            n in 1usize..(2 * TRAVEL_CHUNK + 40),
            seed in proptest::prelude::any::<u64>(),
            m in proptest::array::uniform3(-3.0f32..3.0),
            dt in 1e-4f32..0.05,
            bound in 0.05f32..2.0,
            fast in 0.0f32..0.3,
            specials in crate::test_rng::specials(3),
        ) {
            let mut rng = signed(seed);
            let mut v: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| rng()).collect());
            for i in 0..n {
                let r = rng().abs();
                for a in &mut v {
                    if r < fast {
                        a[i] *= 50.0;
                    } else if r > 0.9 {
                        a[i] = 0.0;
                    }
                }
            }
            for (i, a, k) in specials {
                v[a][i as usize % n] = crate::test_rng::SPECIAL_F32[k];
            }
            let vs = [&v[0][..], &v[1][..], &v[2][..]];
            let rule = TravelRule { m, dt, d: 0.01, bound };
            let bits = |t: &[f32]| t.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            let mut want = vec![0.0f32; n];
            let tally = rule.chunk(vs, &mut want, false);
            proptest::prop_assert_eq!(tally.bins.iter().sum::<usize>(), n);
            let mut got = vec![0.0f32; n];
            proptest::prop_assert_eq!(rule.chunk(vs, &mut got, true), tally);
            proptest::prop_assert_eq!(bits(&got), bits(&want));
            let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
            for exec in [Exec::new(true, true), Exec::new(false, true)] {
                let t = pool.install(|| rule.all(vs, &mut got, exec));
                proptest::prop_assert_eq!(t, tally, "{:?}", exec);
                proptest::prop_assert_eq!(bits(&got), bits(&want), "{:?}", exec);
            }
        }
    }
}
