//! Candidate lists kept across steps (Verlet lists with a skin).
//!
//! The broadphase may run with a skin `s`: it lists each pair within `d + (b_i + b_j) d + s`,
//! `b_i` the particle's travel of the build (at least its travel then), and the candidates are
//! kept while no particle has moved more than `s / 2` (less a rounding margin) since and no
//! particle's travel has passed its `b_i`: two particles then closed in by less than `s`, so
//! every pair within its own reach `d + (t_i + t_j) d` now was a candidate. The filter from
//! candidates to lists ([`within_reach`]) keeps each pair within its own reach (a query without
//! a skin keeps them so itself). Each step's lists are then exactly the lists of a fresh
//! query: the reuse changes the cost, never the result.
//!
//! The skin pays only when the lists then last several steps: a wider reach finds more
//! candidates, and a cloth that moves its skin in a step or two rebuilds anyway. So the skin
//! is `SKIN_FACTOR d` when the particles moved at most a quarter of that a step over the last
//! lists' life, else zero (no candidates kept, the query's lists used as they are).

use crate::data::exec::Exec;
use crate::data::lanes::{gather1, F32s, Idx8, LANES};
use crate::error::Result;
use crate::model::self_collision::SelfBroadphase;
use crate::self_collision::neighbours::{pair_reach2 as reach2, within, Neighbours};

/// The skin in collision distances when the particles move slowly.
const SKIN_FACTOR: f32 = 1.0;

/// The candidates' build and how fast the particles moved since.
#[derive(Clone, Debug, Default)]
pub(crate) struct Reuse {
    /// Positions at the build.
    at: [Vec<f32>; 3],
    /// What the candidates were built for: particle count, distance (bits), broadphase.
    key: Option<(usize, u32, SelfBroadphase)>,
    /// Each particle's travel over `d` the candidates were built for (the skin comes on top).
    travel: Vec<f32>,
    skin: f32,
    /// Steps since the build.
    age: u32,
    /// Largest move a step over the last lists' life (the move since the build over their
    /// age), m.
    rate: f32,
    /// Builds of the candidate lists.
    pub(crate) builds: u64,
}

impl Reuse {
    /// Whether candidates built for distance `d` still hold every pair within its own reach at
    /// the positions `x` and travels `t` (the first `n`); else forgets them.
    pub(crate) fn holds(&mut self, x: [&[f32]; 3], t: &[f32], n: usize, d: f32, broadphase: SelfBroadphase) -> bool {
        self.age += 1;
        let slower = || t.len() >= n && self.travel.len() >= n && at_most(&t[..n], &self.travel[..n]);
        if self.key != Some((n, d.to_bits(), broadphase)) || !slower() {
            self.key = None;
            return false;
        }
        let moved = max_move(x, [&self.at[0], &self.at[1], &self.at[2]], n);
        self.rate = moved / self.age as f32;
        // `moved` is NaN for a non-finite particle: rebuild (the broadphase reports it).
        let keep = moved < 0.49 * self.skin;
        if !keep {
            self.key = None;
        }
        keep
    }

    /// The skin of the next build for distance `d`.
    pub(crate) fn next_skin(&self, d: f32) -> f32 {
        let s = SKIN_FACTOR * d;
        if self.builds > 0 && self.rate <= 0.25 * s {
            s
        } else {
            0.0
        }
    }

    /// Records a build from `x` with `skin` for distance `d`, each particle's travel given by
    /// `travel(i)` (the first `n`).
    pub(crate) fn built(&mut self, x: [&[f32]; 3], n: usize, d: f32, travel: impl Fn(usize) -> f32, broadphase: SelfBroadphase, skin: f32) {
        for (a, src) in self.at.iter_mut().zip(x) {
            a.clear();
            a.extend_from_slice(&src[..n.min(src.len())]);
        }
        self.travel.clear();
        self.travel.extend((0..n).map(travel));
        self.key = Some((n, d.to_bits(), broadphase));
        self.skin = skin;
        self.age = 0;
        self.builds += 1;
    }

    /// The skin of the candidates in use.
    pub(crate) fn skin(&self) -> f32 {
        self.skin
    }
}

/// Whether each of `t` is at most its match in `b` (false for a NaN). No branch an element,
/// so the loop runs in lanes.
fn at_most(t: &[f32], b: &[f32]) -> bool {
    t.iter().zip(b).fold(true, |ok, (t, b)| ok & (t <= b))
}

/// The largest distance one of the first `n` particles moved from `b` to `a` (NaN if any is
/// non-finite). On slices cut to `n` and without a branch a particle, so the loop runs in lanes.
fn max_move(a: [&[f32]; 3], b: [&[f32]; 3], n: usize) -> f32 {
    let (ax, ay, az) = (&a[0][..n], &a[1][..n], &a[2][..n]);
    let (bx, by, bz) = (&b[0][..n], &b[1][..n], &b[2][..n]);
    let (mut m2, mut nan) = (0.0f32, false);
    for i in 0..n {
        let (dx, dy, dz) = (ax[i] - bx[i], ay[i] - by[i], az[i] - bz[i]);
        let d2 = dx * dx + dy * dy + dz * dz;
        nan |= d2.is_nan();
        m2 = if d2 > m2 { d2 } else { m2 };
    }
    if nan {
        f32::NAN
    } else {
        m2.sqrt()
    }
}

/// The lists `out`: the candidates `cand` within reach of each other at `x`, by the
/// broadphase's predicate with the pair's own reach `d + (t_i + t_j) d`, `t` the particles'
/// travels over the collision distance `d` (in parallel over fixed chunks when `exec` is,
/// eight candidates at a time when its lanes are; the same lists).
pub(crate) fn within_reach(cand: &Neighbours, x: [&[f32]; 3], d: f32, t: &[f32], out: &mut Neighbours, exec: Exec) -> Result<()> {
    let simd = exec.simd();
    let keep = |i: usize, buf: &mut Vec<u32>| keep_within(cand.of(i), x, i, d, t, simd, buf);
    if exec.parallel() {
        out.fill_parallel(cand.len(), keep)
    } else {
        out.fill_serial(cand.len(), keep)
    }
}

/// Appends to `buf`, in order, the candidates `js` of particle `i` that pass [`within`] at
/// `x` for their pair's reach (`pair_reach2`). With `simd`, eight at a time: the differences,
/// squares, sums and reaches are [`within`]'s and `pair_reach2`'s operations in their order, so
/// every decision is the scalar loop's (which is the twin, and takes the last candidates);
/// the kept ones are written from a bit mask, without a branch a candidate.
fn keep_within(js: &[u32], x: [&[f32]; 3], i: usize, d: f32, t: &[f32], simd: bool, buf: &mut Vec<u32>) {
    let (xi, yi, zi, ti) = (x[0][i], x[1][i], x[2][i], t[i]);
    let mut done = 0;
    if simd {
        let (vx, vy, vz) = (F32s::splat(xi), F32s::splat(yi), F32s::splat(zi));
        let (dv, tv) = (F32s::splat(d), F32s::splat(ti));
        let blocks = js.chunks_exact(LANES);
        done = js.len() - blocks.remainder().len();
        for c in blocks {
            let idx: Idx8 = c.try_into().expect("a chunk of lane width");
            let dx = gather1(x[0], &idx) - vx;
            let dy = gather1(x[1], &idx) - vy;
            let dz = gather1(x[2], &idx) - vz;
            let r = dv + (tv + gather1(t, &idx)) * dv;
            let mut bits = (dx * dx + dy * dy + dz * dz).simd_le(r * r).to_bitmask();
            while bits != 0 {
                buf.push(c[bits.trailing_zeros() as usize]);
                bits &= bits - 1;
            }
        }
    }
    for &j in &js[done..] {
        let j8 = j as usize;
        if within(xi, yi, zi, x[0][j8], x[1][j8], x[2][j8], reach2(d, ti, t[j8])) {
            buf.push(j);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::signed;

    /// Kept candidates hold while the particles stay within half the skin and each travel
    /// within its travel of the build; a faster particle forgets them.
    #[test]
    fn candidates_hold_only_within_their_travels() {
        let x = [vec![0.0f32, 0.01], vec![0.0; 2], vec![0.0; 2]];
        let xs = [&x[0][..], &x[1][..], &x[2][..]];
        let moved = [vec![0.0f32, 0.0145], vec![0.0; 2], vec![0.0; 2]];
        let ms = [&moved[0][..], &moved[1][..], &moved[2][..]];
        let b = [1.0f32, 0.5];
        let mut r = Reuse::default();
        let hash = SelfBroadphase::Hash;
        r.built(xs, 2, 0.01, |i| b[i], hash, 0.01);
        assert!(r.holds(xs, &b, 2, 0.01, hash));
        assert!(r.holds(ms, &[0.25, 0.5], 2, 0.01, hash));
        assert!(!r.holds(xs, &[0.25, 0.51], 2, 0.01, hash), "one particle faster");
        // forgotten: the same travels no longer hold
        assert!(!r.holds(xs, &b, 2, 0.01, hash));
        r.built(xs, 2, 0.01, |i| b[i], hash, 0.01);
        assert!(!r.holds(xs, &b[..1], 2, 0.01, hash), "travels of too few particles");
        r.built(xs, 2, 0.01, |i| b[i], hash, 0.01);
        let far = [vec![0.0f32, 0.0151], vec![0.0; 2], vec![0.0; 2]];
        assert!(!r.holds([&far[0][..], &far[1][..], &far[2][..]], &b, 2, 0.01, hash));
        r.built(xs, 2, 0.01, |i| b[i], hash, 0.01);
        assert!(!r.holds(xs, &b, 2, 0.01, SelfBroadphase::AabbTree), "another broadphase");
        r.built(xs, 2, 0.01, |i| b[i], hash, 0.01);
        let lost = [vec![0.0f32, 0.01], vec![f32::NAN, 0.0], vec![0.0; 2]];
        assert!(
            !r.holds([&lost[0][..], &lost[1][..], &lost[2][..]], &b, 2, 0.01, hash),
            "a non-finite particle"
        );
        r.built(xs, 2, 0.01, |i| b[i], hash, 0.01);
        assert!(!r.holds(xs, &[0.25, f32::NAN], 2, 0.01, hash), "a non-finite travel");
        r.built(xs, 2, 0.01, |i| b[i], hash, 0.01);
        assert!(r.holds(xs, &b, 2, 0.01, hash), "unmoved, equal travels");
    }

    /// The lane filter keeps exactly the scalar loop's candidates: a random cloud whose
    /// candidates reach twice the radius, with partners exactly at the radius (kept: the rule
    /// is `<=`), just beyond it, and non-finite ones (never kept), on lists of every length
    /// around the lane width; serial and parallel, lanes and scalar give the same lists.
    #[test]
    fn lane_filter_equals_the_scalar_loop() {
        let mut rng = signed(41);
        let n = 300;
        let mut p: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| 0.1 * rng()).collect());
        let q = 0.03f32;
        // Particle 1 sits exactly q from particle 0 along x, particle 2 one ulp beyond.
        for c in &mut p {
            (c[1], c[2]) = (c[0], c[0]);
        }
        (p[0][0], p[0][1], p[0][2]) = (0.0, q, f32::from_bits(q.to_bits() + 1));
        (p[1][5], p[2][6]) = (f32::NAN, f32::INFINITY);
        let x = [&p[0][..], &p[1][..], &p[2][..]];
        let near = |i: usize, j: u32, r2: f32| {
            let j = j as usize;
            within(x[0][i], x[1][i], x[2][i], x[0][j], x[1][j], x[2][j], r2)
        };
        let mut cand = Neighbours::new();
        cand.fill_serial(n, |i, buf| {
            // Lists of 0 to 20 candidates: every tail length after whole lane groups.
            buf.extend((0..n as u32).filter(|&j| j as usize != i && near(i, j, 4.0 * q * q)).take(i % 21));
            if i == 0 {
                // One whole lane group holding the boundary and non-finite partners.
                buf.extend([1, 2, 5, 6, 3, 4, 7, 8]);
            }
        })
        .unwrap();
        let mut want = cand.clone();
        want.retain(|i, j| near(i, j, q * q));
        assert!(
            want.total() > 200 && want.total() < cand.total(),
            "{} of {}",
            want.total(),
            cand.total()
        );
        assert!(want.of(0).contains(&1) && !want.of(0).contains(&2));
        // Distance `q` and travels zero: every pair's reach is `q` exactly.
        let zero = vec![0.0f32; n];
        // Travels of their own: each pair its reach `d + (t_i + t_j) d`.
        let d = q / 3.0;
        let t: Vec<f32> = (0..n).map(|i| 0.25 + 0.125 * (i % 7) as f32).collect();
        let mut own = cand.clone();
        own.retain(|i, j| near(i, j, reach2(d, t[i], t[j as usize])));
        assert!(own.total() > 100 && own != want, "{}", own.total());
        for exec in [
            Exec::new(false, false),
            Exec::new(false, true),
            Exec::new(true, false),
            Exec::new(true, true),
        ] {
            let mut got = Neighbours::new();
            within_reach(&cand, x, q, &zero, &mut got, exec).unwrap();
            assert_eq!(got, want, "{exec:?}");
            within_reach(&cand, x, d, &t, &mut got, exec).unwrap();
            assert_eq!(got, own, "{exec:?}, own travels");
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        /// On random clouds (pairs placed exactly at their reach and one ulp beyond, a few
        /// coordinates and travels replaced by non-finite, huge, signed-zero or subnormal values) with
        /// random candidate lists of every length around the lane width, the lane filter keeps
        /// the scalar loop's candidates, in order, serial and parallel, and those are the pairs
        /// within their own reach.
        #[test]
        fn lane_filter_equals_the_scalar_loop_on_random_clouds(
            n in 2usize..400,
            seed in proptest::prelude::any::<u64>(),
            d in 0.002f32..0.03,
            specials in crate::test_rng::specials(4),
        ) {
            let mut rng = signed(seed);
            let mut p: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| 0.05 * rng()).collect());
            let mut t: Vec<f32> = (0..n).map(|_| 0.25 + 0.75 * rng().abs()).collect();
            // Every fifth particle has its next exactly at their reach along x, or one ulp
            // beyond: the boundary, where a reordered sum would decide otherwise.
            for i in (0..n - 1).step_by(5) {
                let r = d + (t[i] + t[i + 1]) * d;
                p[0][i] = 0.0;
                p[0][i + 1] = if i % 10 == 0 { r } else { f32::from_bits(r.to_bits() + 1) };
                for a in &mut p[1..] {
                    a[i + 1] = a[i];
                }
            }
            for (i, a, k) in specials {
                let v = crate::test_rng::SPECIAL_F32[k];
                let i = i as usize % n;
                if a == 3 {
                    t[i] = v;
                } else {
                    p[a][i] = v;
                }
            }
            let x = [&p[0][..], &p[1][..], &p[2][..]];
            let mut cand = Neighbours::new();
            cand.fill_serial(n, |i, buf| {
                let k = ((rng() + 1.0) * 12.0) as usize;
                buf.extend((0..k).map(|_| ((rng() + 1.0) * 0.5 * n as f32) as u32 % n as u32));
                if i % 5 == 0 && i + 1 < n {
                    buf.push(i as u32 + 1);
                }
            })
            .unwrap();
            let mut want = cand.clone();
            want.retain(|i, j| {
                let j = j as usize;
                within(x[0][i], x[1][i], x[2][i], x[0][j], x[1][j], x[2][j], reach2(d, t[i], t[j]))
            });
            let mut got = Neighbours::new();
            within_reach(&cand, x, d, &t, &mut got, Exec::new(false, false)).unwrap();
            proptest::prop_assert_eq!(&got, &want, "scalar");
            let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
            for exec in [Exec::new(true, false), Exec::new(true, true), Exec::new(false, true)] {
                pool.install(|| within_reach(&cand, x, d, &t, &mut got, exec)).unwrap();
                proptest::prop_assert_eq!(&got, &want, "{:?}", exec);
            }
        }
    }
}
