//! The step's pair list and the per-pair contact of the substep pass (the method is described
//! in [`crate::self_collision`]).

use crate::data::lanes::{gather_xyzw8_unchecked, load_idx_unchecked, F32s, Vec3x8, LANES};
use crate::model::self_collision::Response;
#[cfg(test)]
use crate::self_collision::neighbours::Neighbours;

/// The `i` of every entry of the step's CSR lists, whose `ids` are the `j`: with them the
/// lists read as a structure-of-arrays pair list ([`PairList`]), filled once a step.
#[derive(Clone, Debug, Default)]
pub(crate) struct PairRows {
    i: Vec<u32>,
    /// The largest id of the lists (every gather below it is in bounds).
    top: u32,
}

impl PairRows {
    /// The rows of CSR lists whose entries are the upper partners `j > i` of each `i`.
    pub(crate) fn fill(&mut self, first: &[u32], ids: &[u32]) {
        self.i.clear();
        for (i, w) in first.windows(2).enumerate() {
            let len = w[1].saturating_sub(w[0]) as usize;
            self.i.extend(std::iter::repeat_n(i as u32, len));
        }
        // Every `i` of a pair is below its `j`.
        self.top = ids.iter().copied().max().unwrap_or(0);
    }

    /// The pair list of these rows and the lists' `ids` they were filled with.
    pub(crate) fn list<'a>(&'a self, ids: &'a [u32]) -> PairList<'a> {
        let len = self.i.len().min(ids.len());
        PairList {
            i: &self.i[..len],
            j: &ids[..len],
            top: self.top,
        }
    }
}

/// The step's pairs in structure-of-arrays form: pair `k` is `(i[k], j[k])`, `i < j`, ordered
/// by `i` then `j`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PairList<'a> {
    pub(crate) i: &'a [u32],
    pub(crate) j: &'a [u32],
    /// The largest id in the list (every gather below it is in bounds).
    top: u32,
}

impl PairList<'_> {
    /// Number of pairs.
    pub(crate) fn len(&self) -> usize {
        self.j.len()
    }
}

/// Everything the pair pass reads.
pub(crate) struct PairCtx<'a> {
    pub(crate) x: [&'a [f32]; 3],
    pub(crate) p: [&'a [f32]; 3],
    pub(crate) w: &'a [f32],
    /// Rest positions and cloth ids, one `[x, y, z, cloth]` record a particle (the id's bits
    /// in the fourth lane, [`rest_record`]): a contact reads one record a side.
    pub(crate) rest4: &'a [[f32; 4]],
    pub(crate) d: f32,
    pub(crate) response: Response,
}

/// The rest record of a particle at rest position `r` in cloth `cloth` (see [`PairCtx::rest4`]).
pub(crate) fn rest_record(r: [f32; 3], cloth: u32) -> [f32; 4] {
    [r[0], r[1], r[2], f32::from_bits(cloth)]
}

/// Unit direction separating coincident particles with no rest direction: `(1, 2, 3)/√14`.
const COINCIDENT: [f32; 3] = [0.267_261_24, 0.534_522_5, 0.801_783_7];

impl PairCtx<'_> {
    /// Appends to `out` the pairs `(i[k], j[k])` of `range` of `list` that may be in contact:
    /// closer than `d` at the predicted positions `xyzw` (a copy of `p`, one record a
    /// particle), with a 1e-4 margin so that the exact test of [`PairCtx::pair_contact`]
    /// makes every decision and both backends find the same contacts. Eight pairs at a time
    /// when `simd`, else one by one (the scalar twin); the differences and squares are the same
    /// operations either way.
    pub(crate) fn touching(
        &self,
        list: PairList<'_>,
        range: std::ops::Range<usize>,
        xyzw: &[[f32; 4]],
        simd: bool,
        out: &mut Vec<(u32, u32)>,
    ) {
        let lim = self.d * self.d * 1.0001;
        let (li, lj) = (&list.i[range.clone()], &list.j[range]);
        let mut done = 0;
        // Every index below the records' length, checked once, so the gathers need no checks.
        if simd && (list.top as usize) < xyzw.len() {
            let limv = F32s::splat(lim);
            let groups = li.len() / LANES;
            for g in 0..groups {
                let o = g * LANES;
                // SAFETY: `o + LANES <= li.len() == lj.len()`; every id is at most
                // `list.top < xyzw.len()` (checked above).
                let (a, b) = unsafe {
                    let b = gather_xyzw8_unchecked(xyzw, &load_idx_unchecked(lj, o));
                    // The list is sorted by `i`: eight pairs mostly share it, then one record
                    // broadcast (the same values as the gather).
                    let a = if li[o] == li[o + LANES - 1] {
                        xyzw.get_unchecked(li[o] as usize).map(F32s::splat)
                    } else {
                        gather_xyzw8_unchecked(xyzw, &load_idx_unchecked(li, o))
                    };
                    (a, b)
                };
                let v = Vec3x8 {
                    x: a[0] - b[0],
                    y: a[1] - b[1],
                    z: a[2] - b[2],
                };
                let mut bits = v.length_sq().simd_lt(limv).to_bitmask();
                while bits != 0 {
                    let l = o + bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    out.push((li[l], lj[l]));
                }
            }
            done = groups * LANES;
        }
        for (&i, &j) in li[done..].iter().zip(&lj[done..]) {
            let (a, b) = (xyzw[i as usize], xyzw[j as usize]);
            let v = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
            if v[0] * v[0] + v[1] * v[1] + v[2] * v[2] < lim {
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
            let (ra, rb) = (self.rest4[i], self.rest4[j]);
            let same = ra[3].to_bits() == rb[3].to_bits();
            let r = [ra[0] - rb[0], ra[1] - rb[1], ra[2] - rb[2]];
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
