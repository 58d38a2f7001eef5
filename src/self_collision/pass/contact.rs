//! The contact of one listed pair, computed once for both particles ([`PairContact`]): the
//! scalar form ([`PairCtx::pair_contact`], the twin) and eight pairs at a time
//! ([`PairCtx::pair_contacts`]), the same bits.

use wide::u32x8;

use crate::data::lanes::{gather1_unchecked, gather_xyzw8_unchecked, idx8, F32s, Idx8, Vec3x8, LANES};
use crate::model::self_collision::Response;
use crate::self_collision::pass::pairs::PairCtx;
use crate::self_collision::pass::sums::Record;

/// Unit direction separating coincident particles with no rest direction: `(1, 2, 3)/√14`.
pub(crate) const COINCIDENT: [f32; 3] = [0.267_261_24, 0.534_522_5, 0.801_783_7];

impl PairCtx<'_> {
    /// The contact of the pair `(i, j)`, computed once for both particles, or `None` when the
    /// pair is not in contact or neither particle is free. Adding its two sides
    /// ([`PairContact::add_to`]) gives the same bits as [`PairCtx::add_contact`] run from each
    /// end: the geometry of `(j, i)` is that of `(i, j)` negated (IEEE subtraction and division
    /// are exact under negation; a zero can only change sign, which no sum sees, see
    /// [`PairContact`]), the squared distances and the mass sum `w_i + w_j` are the same.
    ///
    /// The predicted positions and inverse masses are read from `xyzw` (`[x, y, z, w]`
    /// records of `p` and `w`), the rest data from [`PairCtx::rest4`]: one record a side
    /// for each (the start positions `x` are read from their arrays).
    #[inline]
    pub(crate) fn pair_contact(&self, xyzw: &[[f32; 4]], i: usize, j: usize) -> Option<PairContact> {
        let (a, b) = (xyzw[i], xyzw[j]);
        let (wi, wj) = (a[3], b[3]);
        if wi <= 0.0 && wj <= 0.0 {
            return None;
        }
        let pi = [a[0], a[1], a[2]];
        let pj = [b[0], b[1], b[2]];
        let v = [pi[0] - pj[0], pi[1] - pj[1], pi[2] - pj[2]];
        let dist2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        let d2 = self.d * self.d;
        // min_dist <= d: most listed pairs end here, before the rest data is read.
        if dist2.is_nan() || dist2 >= d2 {
            return None;
        }
        let (ra, rb) = (self.rest4[i], self.rest4[j]);
        let same = ra[3].to_bits() == rb[3].to_bits();
        let r = [ra[0] - rb[0], ra[1] - rb[1], ra[2] - rb[2]];
        let rest2 = if same {
            r[0] * r[0] + r[1] * r[1] + r[2] * r[2]
        } else {
            f32::INFINITY
        };
        if dist2 > rest2 {
            return None;
        }
        let md = if rest2 < d2 { rest2.sqrt() } else { self.d };
        if dist2 >= md * md {
            return None;
        }
        let dist = dist2.sqrt();
        let nrm = if dist2 > 0.0 {
            v.map(|c| c / dist)
        } else if same && rest2 > 0.0 {
            let rl = rest2.sqrt();
            r.map(|c| c / rl)
        } else {
            // `i < j` here (the pair list's order); the reverse side gets the negation.
            let s = if i < j { 1.0 } else { -1.0 };
            COINCIDENT.map(|c| c * s)
        };
        let wsum = wi + wj;
        let share = [wi / wsum, wj / wsum];
        let di = [pi[0] - self.x[0][i], pi[1] - self.x[1][i], pi[2] - self.x[2][i]];
        let dj = [pj[0] - self.x[0][j], pj[1] - self.x[1][j], pj[2] - self.x[2][j]];
        let (amount, approaching) = if self.response == Response::MovementSpeed {
            let vn = (di[0] - dj[0]) * nrm[0] + (di[1] - dj[1]) * nrm[1] + (di[2] - dj[2]) * nrm[2];
            if vn < 0.0 {
                ([-vn * share[0], -vn * share[1]], true)
            } else {
                ([0.0; 2], false)
            }
        } else {
            ([(md - dist) * share[0], (md - dist) * share[1]], false)
        };
        Some(PairContact {
            nrm,
            amount,
            free: [wi > 0.0, wj > 0.0],
            disp: [di, dj],
            gap: dist - md,
            approaching,
        })
    }

    /// The contacts of the pairs `near` (each `(i, j)` with `i < j`), appended to `out` in
    /// order: [`PairCtx::pair_contact`] of each pair. With `simd`, eight pairs at a time: every
    /// lane computes all of the scalar test's values with the same operations and the lanes
    /// the scalar test would leave early are dropped, so the contacts are the same bits; the
    /// last pairs, a group with an id past the arrays (whose checked reads then fail), and
    /// every pair without `simd`, one by one.
    pub(crate) fn pair_contacts(&self, xyzw: &[[f32; 4]], near: &[(u32, u32)], simd: bool, out: &mut Vec<Option<PairContact>>) {
        let n = [xyzw.len(), self.rest4.len(), self.x[0].len(), self.x[1].len(), self.x[2].len()]
            .into_iter()
            .min()
            .unwrap_or(0);
        let scalar = |out: &mut Vec<Option<PairContact>>, g: &[(u32, u32)]| {
            out.extend(g.iter().map(|&(i, j)| self.pair_contact(xyzw, i as usize, j as usize)));
        };
        let groups = if simd { near.len() / LANES } else { 0 };
        for g in near[..groups * LANES].chunks_exact(LANES) {
            let ii = idx8(|l| g[l].0);
            let jj = idx8(|l| g[l].1);
            let top = (u32x8::from(ii).max(u32x8::from(jj))).to_array().into_iter().max().unwrap_or(0);
            if (top as usize) < n {
                // SAFETY: every id of the group is below each array's length (checked above).
                unsafe { self.contacts8(xyzw, &ii, &jj, out) };
            } else {
                scalar(out, g);
            }
        }
        scalar(out, &near[groups * LANES..]);
    }

    /// Eight lanes of [`PairCtx::pair_contact`] (see [`PairCtx::pair_contacts`]).
    ///
    /// # Safety
    /// Every id of `ii` and `jj` is below the lengths of `xyzw`, `rest4` and the three arrays
    /// of `x`.
    #[inline(always)]
    unsafe fn contacts8(&self, xyzw: &[[f32; 4]], ii: &Idx8, jj: &Idx8, out: &mut Vec<Option<PairContact>>) {
        // SAFETY: in bounds by the caller's guarantee.
        let (a, b, ra, rb, xi, xj) = unsafe {
            (
                gather_xyzw8_unchecked(xyzw, ii),
                gather_xyzw8_unchecked(xyzw, jj),
                gather_xyzw8_unchecked(self.rest4, ii),
                gather_xyzw8_unchecked(self.rest4, jj),
                Vec3x8 {
                    x: gather1_unchecked(self.x[0], ii),
                    y: gather1_unchecked(self.x[1], ii),
                    z: gather1_unchecked(self.x[2], ii),
                },
                Vec3x8 {
                    x: gather1_unchecked(self.x[0], jj),
                    y: gather1_unchecked(self.x[1], jj),
                    z: gather1_unchecked(self.x[2], jj),
                },
            )
        };
        let zero = F32s::splat(0.0);
        let (wi, wj) = (a[3], b[3]);
        let pi = Vec3x8 { x: a[0], y: a[1], z: a[2] };
        let pj = Vec3x8 { x: b[0], y: b[1], z: b[2] };
        let v = pi - pj;
        let dist2 = v.length_sq();
        let d = F32s::splat(self.d);
        let d2 = F32s::splat(self.d * self.d);
        let same = bytemuck::cast::<F32s, u32x8>(ra[3]).simd_eq(bytemuck::cast::<F32s, u32x8>(rb[3]));
        let same = bytemuck::cast::<u32x8, F32s>(same);
        let r = Vec3x8 {
            x: ra[0] - rb[0],
            y: ra[1] - rb[1],
            z: ra[2] - rb[2],
        };
        let rest2 = same.select(r.length_sq(), F32s::splat(f32::INFINITY));
        let rl = rest2.sqrt();
        let md = rest2.simd_lt(d2).select(rl, d);
        // The scalar test's early exits, as one mask: a free particle, closer than `d`, not
        // farther apart than at rest, closer than `min_dist`.
        let keep = !(wi.simd_le(zero) & wj.simd_le(zero)) & dist2.simd_lt(d2) & !dist2.simd_gt(rest2) & !dist2.simd_ge(md * md);
        let mut bits = keep.to_bitmask();
        if bits == 0 {
            out.extend([None; LANES]);
            return;
        }
        let dist = dist2.sqrt();
        let sign = F32s::from(std::array::from_fn::<f32, LANES, _>(|l| if ii[l] < jj[l] { 1.0 } else { -1.0 }));
        let coincident = Vec3x8::splat(COINCIDENT).scale(sign);
        let nrm = Vec3x8::select(
            dist2.simd_gt(zero),
            v / dist,
            Vec3x8::select(same & rest2.simd_gt(zero), r / rl, coincident),
        );
        let wsum = wi + wj;
        let share = [wi / wsum, wj / wsum];
        let di = pi - xi;
        let dj = pj - xj;
        let (amount, approaching) = if self.response == Response::MovementSpeed {
            let vn = (di.x - dj.x) * nrm.x + (di.y - dj.y) * nrm.y + (di.z - dj.z) * nrm.z;
            let neg = vn.simd_lt(zero);
            (
                [neg.select(-vn * share[0], zero), neg.select(-vn * share[1], zero)],
                neg.to_bitmask(),
            )
        } else {
            let gap = md - dist;
            ([gap * share[0], gap * share[1]], 0)
        };
        let gap = dist - md;
        let (wi, wj) = (wi.to_array(), wj.to_array());
        let nrm = [nrm.x.to_array(), nrm.y.to_array(), nrm.z.to_array()];
        let amount = [amount[0].to_array(), amount[1].to_array()];
        let disp = [
            di.x.to_array(),
            di.y.to_array(),
            di.z.to_array(),
            dj.x.to_array(),
            dj.y.to_array(),
            dj.z.to_array(),
        ];
        let gap = gap.to_array();
        let base = out.len();
        out.extend([None; LANES]);
        let slots = &mut out[base..];
        while bits != 0 {
            let l = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            slots[l] = Some(PairContact {
                nrm: [nrm[0][l], nrm[1][l], nrm[2][l]],
                amount: [amount[0][l], amount[1][l]],
                free: [wi[l] > 0.0, wj[l] > 0.0],
                disp: [[disp[0][l], disp[1][l], disp[2][l]], [disp[3][l], disp[4][l], disp[5][l]]],
                gap: gap[l],
                approaching: approaching >> l & 1 == 1,
            });
        }
    }
}

/// One contact as seen from both of its particles (from [`PairCtx::pair_contact`]).
///
/// Side 0 is `i`, side 1 is `j`; side 1's normal is side 0's negated. The sums start at `+0`
/// and never become `-0`, so adding `-0` or `+0` for a zero component gives the same bits: the
/// only difference from the one-sided computation (a zero coordinate difference is `+0` from
/// both ends) is invisible.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PairContact {
    nrm: [f32; 3],
    amount: [f32; 2],
    free: [bool; 2],
    disp: [[f32; 3]; 2],
    gap: f32,
    approaching: bool,
}

impl PairContact {
    /// Adds the contact to side `side`'s record (`[c(3), f(3), n(3), gap, count]` and the
    /// approaching count), if that particle is free; returns whether it was. The twelve
    /// values are added as one array, without a branch: each is one addition, the operations
    /// of [`PairCtx::add_contact`], and a contact that does not approach adds `+0` to a count
    /// that is never `-0`, which changes no bit.
    #[inline]
    pub(crate) fn add_to(&self, side: usize, rec: &mut Record) -> bool {
        if !self.free[side] {
            return false;
        }
        let sign = if side == 0 { 1.0f32 } else { -1.0 };
        let amount = self.amount[side];
        // The partner's displacement.
        let f = self.disp[1 - side];
        let n = self.nrm.map(|c| c * sign);
        let add: Record = [
            n[0] * amount,
            n[1] * amount,
            n[2] * amount,
            f[0],
            f[1],
            f[2],
            n[0],
            n[1],
            n[2],
            self.gap,
            1.0,
            if self.approaching { 1.0 } else { 0.0 },
        ];
        for (r, a) in rec.iter_mut().zip(add) {
            *r += a;
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::self_collision::pass::pairs::rest_record;

    impl PairContact {
        /// Every value's bits, the flags as 0 or 1.
        fn bits(&self) -> Vec<u32> {
            let f = self
                .nrm
                .iter()
                .chain(&self.amount)
                .chain(self.disp.iter().flatten())
                .chain([&self.gap]);
            f.map(|v| v.to_bits())
                .chain(self.free.map(u32::from))
                .chain([u32::from(self.approaching)])
                .collect()
        }
    }

    /// Compares the eight-lane contacts with the scalar twin's bit for bit on `n` crowded
    /// particles of two cloths (pinned particles, coincident predictions, coincident rest
    /// positions, pairs closer at rest than `d`), for both kinds of response, and counts the
    /// contacts at a distance, of coincident particles by their rest direction and of
    /// coincident particles without one.
    fn lanes_against_scalar(n: usize, seed: u64) -> [usize; 3] {
        let mut r = crate::test_rng::signed(seed | 1);
        let d = 0.03f32;
        let mut p: Vec<[f32; 3]> = (0..n).map(|_| [0.02 * r(), 0.02 * r(), 0.02 * r()]).collect();
        let mut rest: Vec<[f32; 3]> = (0..n).map(|_| [0.04 * r(), 0.04 * r(), 0.0]).collect();
        for k in 1..n {
            if r() > 0.7 {
                p[k] = p[k - 1];
            }
            if r() > 0.7 {
                rest[k] = rest[k - 1];
            }
        }
        let x: [Vec<f32>; 3] = std::array::from_fn(|a| p.iter().map(|q| q[a] - 0.01 * r()).collect());
        let xyzw: Vec<[f32; 4]> = p
            .iter()
            .map(|q| [q[0], q[1], q[2], if r() > 0.7 { 0.0 } else { 1.0 + r() }])
            .collect();
        let w: Vec<f32> = xyzw.iter().map(|q| q[3]).collect();
        let rest4: Vec<[f32; 4]> = rest.iter().map(|q| rest_record(*q, u32::from(r() > 0.5))).collect();
        let near: Vec<(u32, u32)> = (0..n as u32)
            .flat_map(|i| (i + 1..n as u32).map(move |j| (i, j)))
            .filter(|_| r() > 0.3)
            .collect();
        let mut kinds = [0usize; 3];
        for response in [Response::Pbd, Response::MovementSpeed] {
            let ctx = PairCtx {
                x: [&x[0], &x[1], &x[2]],
                p: [&x[0], &x[1], &x[2]],
                w: &w,
                rest4: &rest4,
                d,
                response,
            };
            let (mut lanes, mut scalar) = (Vec::new(), Vec::new());
            ctx.pair_contacts(&xyzw, &near, true, &mut lanes);
            ctx.pair_contacts(&xyzw, &near, false, &mut scalar);
            assert_eq!((lanes.len(), scalar.len()), (near.len(), near.len()));
            for ((a, b), &(i, j)) in lanes.iter().zip(&scalar).zip(&near) {
                assert_eq!(a.map(|c| c.bits()), b.map(|c| c.bits()), "pair ({i}, {j})");
                if let Some(c) = a {
                    let (i, j) = (i as usize, j as usize);
                    let coincident = p[i] == p[j];
                    let by_rest = coincident && rest4[i][3] == rest4[j][3] && rest[i] != rest[j];
                    kinds[usize::from(coincident) + usize::from(!by_rest && coincident)] += 1;
                    assert!(c.nrm.iter().all(|v| v.is_finite()), "pair ({i}, {j})");
                }
            }
        }
        kinds
    }

    /// A pair naming a particle past the arrays fails the checked scalar read (a panic, not an
    /// unchecked read), in a full group of eight as in the tail.
    #[test]
    #[should_panic]
    fn an_id_past_the_arrays_is_read_with_checks() {
        let xyzw = vec![[0.0f32; 4]; 8];
        let rest4 = vec![[0.0f32; 4]; 8];
        let (x, w) = (vec![0.0f32; 8], vec![1.0f32; 8]);
        let ctx = PairCtx {
            x: [&x, &x, &x],
            p: [&x, &x, &x],
            w: &w,
            rest4: &rest4,
            d: 0.03,
            response: Response::Pbd,
        };
        let near: Vec<(u32, u32)> = (0..8).map(|k| (k, if k == 5 { 8 } else { k + 1 })).collect();
        ctx.pair_contacts(&xyzw, &near, true, &mut Vec::new());
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]
        /// The eight-lane contacts equal the scalar twin's on random crowds of any size.
        #[test]
        fn contact_lanes_equal_the_scalar_contact(n in 1usize..120, seed in proptest::prelude::any::<u64>()) {
            lanes_against_scalar(n, seed);
        }
    }

    /// Over a few crowds, every kind of contact occurs (so the comparison above covers each
    /// branch of the scalar contact).
    #[test]
    fn every_kind_of_contact_is_compared() {
        let mut kinds = [0usize; 3];
        for seed in 1..=12 {
            let k = lanes_against_scalar(40, seed);
            (0..3).for_each(|a| kinds[a] += k[a]);
        }
        assert!(kinds.iter().all(|&k| k > 0), "{kinds:?}");
    }
}
