//! The self-collision pair pass: the contact sums of one particle over its pair list (the
//! method is described in [`crate::self_collision`]).

use crate::data::lanes::{gather1_unchecked, idx8, F32s, Vec3x8, LANES};
use crate::model::self_collision::Response;
use crate::self_collision::near::scan::largest_id;
use crate::self_collision::neighbours::within;
#[cfg(test)]
use crate::self_collision::neighbours::Neighbours;

/// Everything the pair pass reads.
pub(crate) struct PairCtx<'a> {
    pub(crate) x: [&'a [f32]; 3],
    pub(crate) p: [&'a [f32]; 3],
    pub(crate) w: &'a [f32],
    pub(crate) rest: [&'a [f32]; 3],
    pub(crate) cloth_of: &'a [u32],
    /// Positions at the start of the step (the lists' positions).
    pub(crate) start: [&'a [f32]; 3],
    /// Squared query radius: a pair is in the step's lists when within it at the start.
    pub(crate) q2: f32,
    pub(crate) d: f32,
    pub(crate) response: Response,
}

/// Unit direction separating coincident particles with no rest direction: `(1, 2, 3)/√14`.
const COINCIDENT: [f32; 3] = [0.267_261_24, 0.534_522_5, 0.801_783_7];

impl PairCtx<'_> {
    /// Appends to `out` the near pairs `(i, j)` that may be in contact: closer than `d` (with
    /// a 1e-4 margin, so the exact test of [`PairCtx::contact`] makes every decision and both
    /// paths lead to the same sums) and in the lists of the step (within `q` at its start,
    /// the broadphase's predicate). Eight pairs at a time (`f32x8` on gathered predicted
    /// positions) when `simd`, else one by one.
    pub(crate) fn near_candidates(&self, pairs: &[(u32, u32)], simd: bool, out: &mut Vec<(u32, u32)>) {
        let lim = self.d * self.d * 1.0001;
        let s = self.start;
        let listed = |i: usize, j: usize| within(s[0][i], s[1][i], s[2][i], s[0][j], s[1][j], s[2][j], self.q2);
        let mut done = 0;
        // Every index below the arrays' length, checked once, so the gathers need no checks.
        let len = self.p.iter().map(|a| a.len()).min().unwrap_or(0);
        let top = largest_id(pairs);
        if simd && (top as usize) < len {
            let limv = F32s::splat(lim);
            let groups = pairs.as_chunks::<LANES>().0;
            for group in groups {
                let ii = idx8(|l| group[l].0);
                let jj = idx8(|l| group[l].1);
                // SAFETY: every index of `pairs` is at most `top < len` (checked above).
                let g = |a: &[f32], side: usize| unsafe { gather1_unchecked(a, if side == 0 { &ii } else { &jj }) };
                let v = Vec3x8 {
                    x: g(self.p[0], 0) - g(self.p[0], 1),
                    y: g(self.p[1], 0) - g(self.p[1], 1),
                    z: g(self.p[2], 0) - g(self.p[2], 1),
                };
                let mut bits = v.length_sq().simd_lt(limv).to_bitmask();
                while bits != 0 {
                    let (i, j) = group[bits.trailing_zeros() as usize];
                    bits &= bits - 1;
                    if listed(i as usize, j as usize) {
                        out.push((i, j));
                    }
                }
            }
            done = groups.len() * LANES;
        }
        for &(i, j) in &pairs[done..] {
            let (iu, ju) = (i as usize, j as usize);
            let v = [
                self.p[0][iu] - self.p[0][ju],
                self.p[1][iu] - self.p[1][ju],
                self.p[2][iu] - self.p[2][ju],
            ];
            if v[0] * v[0] + v[1] * v[1] + v[2] * v[2] < lim && listed(iu, ju) {
                out.push((i, j));
            }
        }
    }

    /// Adds the contact of `i` with `j` to `i`'s sums `out` (`[c(3), f(3), n(3), gap, count]`
    /// and the approaching count), if `i` is free and the pair is in contact (one-sided: the
    /// reference of the pair form).
    #[cfg(test)]
    pub(crate) fn add_contact(&self, i: usize, j: usize, out: &mut [f32; 11], approaching: &mut f32) {
        if self.w[i] <= 0.0 {
            return;
        }
        let pi = [self.p[0][i], self.p[1][i], self.p[2][i]];
        let di = [pi[0] - self.x[0][i], pi[1] - self.x[1][i], pi[2] - self.x[2][i]];
        self.contact(i, j, pi, di, self.d * self.d, out, approaching);
    }

    /// Scales the summed movement-speed corrections from the contact count to the approaching
    /// count (the kernel divides by all contacts; the velocity response averages over the
    /// approaching ones only).
    #[inline]
    pub(crate) fn finish(out: &mut [f32; 11], approaching: f32) {
        if approaching > 0.0 {
            let scale = out[10] / approaching;
            for c in &mut out[..3] {
                *c *= scale;
            }
        }
    }

    /// `[c(3), f(3), n(3), gap, count]` of particle `i` over its whole list, ascending: the
    /// per-particle form of the pair pass (the reference the tests hold the pair form to).
    #[cfg(test)]
    pub(crate) fn sums(&self, lists: &Neighbours, i: usize) -> [f32; 11] {
        let mut out = [0.0f32; 11];
        let mut approaching = 0.0f32;
        for &j in lists.of(i) {
            self.add_contact(i, j as usize, &mut out, &mut approaching);
        }
        Self::finish(&mut out, approaching);
        out
    }

    /// Adds the contact of `i` with `j`, if any, to `out` (the one-sided form, kept as the
    /// tests' reference for [`PairCtx::pair_contact`]).
    #[cfg(test)]
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn contact(&self, i: usize, j: usize, pi: [f32; 3], di: [f32; 3], d2: f32, out: &mut [f32; 11], approaching: &mut f32) {
        let wi = self.w[i];
        {
            let v = [pi[0] - self.p[0][j], pi[1] - self.p[1][j], pi[2] - self.p[2][j]];
            let dist2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            // min_dist <= d: most listed pairs end here, before the rest data is read.
            if dist2.is_nan() || dist2 >= d2 {
                return;
            }
            let same = self.cloth_of[i] == self.cloth_of[j];
            let r = [
                self.rest[0][i] - self.rest[0][j],
                self.rest[1][i] - self.rest[1][j],
                self.rest[2][i] - self.rest[2][j],
            ];
            let rest2 = if same {
                r[0] * r[0] + r[1] * r[1] + r[2] * r[2]
            } else {
                f32::INFINITY
            };
            if dist2 > rest2 {
                return;
            }
            let md = if rest2 < self.d * self.d { rest2.sqrt() } else { self.d };
            if dist2.is_nan() || dist2 >= md * md {
                return;
            }
            let dist = dist2.sqrt();
            let nrm = if dist2 > 0.0 {
                v.map(|c| c / dist)
            } else if same && rest2 > 0.0 {
                let rl = rest2.sqrt();
                r.map(|c| c / rl)
            } else {
                let s = if i < j { 1.0 } else { -1.0 };
                COINCIDENT.map(|c| c * s)
            };
            let wj = self.w[j];
            let share = wi / (wi + wj);
            let dj = [
                self.p[0][j] - self.x[0][j],
                self.p[1][j] - self.x[1][j],
                self.p[2][j] - self.x[2][j],
            ];
            let amount = if self.response == Response::MovementSpeed {
                let vn = (di[0] - dj[0]) * nrm[0] + (di[1] - dj[1]) * nrm[1] + (di[2] - dj[2]) * nrm[2];
                if vn < 0.0 {
                    *approaching += 1.0;
                    -vn * share
                } else {
                    0.0
                }
            } else {
                (md - dist) * share
            };
            for a in 0..3 {
                out[a] += nrm[a] * amount;
                out[3 + a] += dj[a];
                out[6 + a] += nrm[a];
            }
            out[9] += dist - md;
            out[10] += 1.0;
        }
    }

    /// The contact of the pair `(i, j)`, computed once for both particles, or `None` when the
    /// pair is not in contact or neither particle is free. Adding its two sides
    /// ([`PairContact::add_to`]) gives the same bits as [`PairCtx::add_contact`] run from each
    /// end: the geometry of `(j, i)` is that of `(i, j)` negated (IEEE subtraction and division
    /// are exact under negation; a zero can only change sign, which no sum sees, see
    /// [`PairContact`]), the squared distances and the mass sum `w_i + w_j` are the same.
    #[inline]
    pub(crate) fn pair_contact(&self, i: usize, j: usize) -> Option<PairContact> {
        let (wi, wj) = (self.w[i], self.w[j]);
        if wi <= 0.0 && wj <= 0.0 {
            return None;
        }
        let pi = [self.p[0][i], self.p[1][i], self.p[2][i]];
        let v = [pi[0] - self.p[0][j], pi[1] - self.p[1][j], pi[2] - self.p[2][j]];
        let dist2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        let d2 = self.d * self.d;
        // min_dist <= d: most listed pairs end here, before the rest data is read.
        if dist2.is_nan() || dist2 >= d2 {
            return None;
        }
        let same = self.cloth_of[i] == self.cloth_of[j];
        let r = [
            self.rest[0][i] - self.rest[0][j],
            self.rest[1][i] - self.rest[1][j],
            self.rest[2][i] - self.rest[2][j],
        ];
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
            // `i < j` here (the near list's order); the reverse side gets the negation.
            let s = if i < j { 1.0 } else { -1.0 };
            COINCIDENT.map(|c| c * s)
        };
        let wsum = wi + wj;
        let share = [wi / wsum, wj / wsum];
        let di = [pi[0] - self.x[0][i], pi[1] - self.x[1][i], pi[2] - self.x[2][i]];
        let dj = [
            self.p[0][j] - self.x[0][j],
            self.p[1][j] - self.x[1][j],
            self.p[2][j] - self.x[2][j],
        ];
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
    /// Adds the contact to side `side`'s sums `[c(3), f(3), n(3), gap, count]` and
    /// approaching count, if that particle is free (the order of operations of
    /// [`PairCtx::add_contact`]).
    /// Returns whether anything was added.
    #[inline]
    pub(crate) fn add_to(&self, side: usize, out: &mut [f32; 11], approaching: &mut f32) -> bool {
        if !self.free[side] {
            return false;
        }
        let sign = if side == 0 { 1.0f32 } else { -1.0 };
        let amount = self.amount[side];
        // The partner's displacement.
        let f = self.disp[1 - side];
        if self.approaching {
            *approaching += 1.0;
        }
        for a in 0..3 {
            let n = self.nrm[a] * sign;
            out[a] += n * amount;
            out[3 + a] += f[a];
            out[6 + a] += n;
        }
        out[9] += self.gap;
        out[10] += 1.0;
        true
    }
}
