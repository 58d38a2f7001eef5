//! The step's pair list and the lane test of the substep pass that finds the pairs in contact
//! range (the method is described in [`crate::self_collision`]); their contacts are computed
//! in [`contact`](super::contact), and held in the tests to the one-sided, particle by
//! particle reference here (`PairCtx::sums`).

use crate::data::lanes::{gather_xyzw8_unchecked, load_idx_unchecked, F32s, Vec3x8, LANES};
use crate::model::self_collision::Response;
#[cfg(test)]
use crate::self_collision::neighbours::Neighbours;
#[cfg(test)]
use crate::self_collision::pass::contact::COINCIDENT;
#[cfg(test)]
use crate::self_collision::pass::sums::{finished, RECORD};

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

    /// `[c(3), f(3), n(3), gap, count]` of particle `i` over its whole list, ascending: the
    /// per-particle form of the pair pass (the reference the tests hold the pair form to).
    #[cfg(test)]
    pub(crate) fn sums(&self, lists: &Neighbours, i: usize) -> [f32; 11] {
        let mut out = [0.0f32; 11];
        let mut approaching = 0.0f32;
        for &j in lists.of(i) {
            self.add_contact(i, j as usize, &mut out, &mut approaching);
        }
        let mut rec = [0.0f32; RECORD];
        rec[..11].copy_from_slice(&out);
        rec[11] = approaching;
        finished(&rec)
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
}
