//! The lane test of one particle (a probe) against a range of slots (module `cells`): the
//! distance within reach, another particle, not a rest neighbour, each kept pair emitted as
//! `(min, max)`. Eight slots at a time, or one at a time (the scalar twin); both decide alike.

use super::{Probe, Reach};
use crate::data::lanes::{load, load_idx, load_idx_unchecked, load_unchecked, F32s, Vec3x8, LANES};
use crate::self_collision::hash::SpatialHash;
use crate::self_collision::neighbours::{pair_reach2, within};
use wide::u32x8;

impl SpatialHash {
    /// Emits `(min, max)` for each kept partner of `q` among slots `s..e` (itself excluded).
    #[inline(always)]
    pub(super) fn pair_scan<const SIMD: bool>(&self, q: &Probe, k: Reach, s: usize, e: usize, buf: &mut Vec<u32>) {
        if SIMD {
            self.pair_scan_lanes(q, k, s, e, buf);
        } else {
            self.pair_scan_scalar(q, k, s, e, buf);
        }
    }

    /// The scalar twin of [`SpatialHash::pair_scan_lanes`].
    fn pair_scan_scalar(&self, q: &Probe, k: Reach, s: usize, e: usize, buf: &mut Vec<u32>) {
        for c in s..e {
            if self.kept(q, k, c) {
                let j = self.rest.ids[c];
                buf.extend([q.i.min(j), q.i.max(j)]);
            }
        }
    }

    /// Whether the particle in slot `c` is kept as a partner of `q`: another particle,
    /// within reach, not a rest neighbour (the scalar decision of the lanes).
    #[inline(always)]
    fn kept(&self, q: &Probe, k: Reach, c: usize) -> bool {
        let rc = &self.rest;
        let (dx, dy, dz) = (q.r[0] - rc.x[c], q.r[1] - rc.y[c], q.r[2] - rc.z[c]);
        let reach2 = k.own.map_or(k.md2, |d| pair_reach2(d, q.t, rc.travel[c]));
        rc.ids[c] != q.i
            && within(q.p[0], q.p[1], q.p[2], self.sx[c], self.sy[c], self.sz[c], reach2)
            && !(rc.cloth[c] == q.cloth && dx * dx + dy * dy + dz * dz <= k.s2)
    }

    /// Slots `s..e` eight at a time: distance, identity, cloth and rest distance, each
    /// computed like [`SpatialHash::pair_scan_scalar`] (no FMA). Every group runs all four
    /// tests: whether a group has a lane within reach follows no pattern the branch predictor
    /// learns (in a settled cloth most do, all of them rest neighbours), and the missed
    /// guesses cost more than the rest test's five loads.
    #[inline(always)]
    fn pair_scan_lanes(&self, q: &Probe, k: Reach, s: usize, e: usize, buf: &mut Vec<u32>) {
        if e + LANES <= k.len {
            self.pair_scan_lanes_with::<false>(q, k, s, e, buf);
        } else {
            self.pair_scan_lanes_with::<true>(q, k, s, e, buf);
        }
    }

    /// [`SpatialHash::pair_scan_lanes`] with bounds-checked loads (`CHECKED`) or, when the
    /// caller found `e + LANES <= k.len`, without.
    #[inline(always)]
    fn pair_scan_lanes_with<const CHECKED: bool>(&self, q: &Probe, k: Reach, s: usize, e: usize, buf: &mut Vec<u32>) {
        // SAFETY (the unchecked loads): every group starts at `c < e` and `e + LANES <= k.len`,
        // the shortest array read, so `c + LANES` stays inside each of them.
        let ld = |a: &[f32], c: usize| if CHECKED { load(a, c) } else { unsafe { load_unchecked(a, c) } };
        let ld_idx = |a: &[u32], c: usize| {
            if CHECKED {
                load_idx(a, c)
            } else {
                unsafe { load_idx_unchecked(a, c) }
            }
        };
        let rc = &self.rest;
        let (pv, m2) = (Vec3x8::splat(q.p), F32s::splat(k.md2));
        let (dv, tq) = (F32s::splat(k.own.unwrap_or(0.0)), F32s::splat(q.t));
        let mut c = s;
        while c < e {
            let d = Vec3x8 {
                x: ld(&self.sx, c),
                y: ld(&self.sy, c),
                z: ld(&self.sz, c),
            } - pv;
            let reach2 = if k.own.is_some() {
                let r = dv + (tq + ld(&rc.travel, c)) * dv;
                r * r
            } else {
                m2
            };
            let mut bits = (d.x * d.x + d.y * d.y + d.z * d.z).simd_le(reach2).to_bitmask();
            if e - c < LANES {
                bits &= (1u32 << (e - c)) - 1;
            }
            // The rest test without a branch on `bits` (see the doc comment).
            let ids = u32x8::from(ld_idx(&rc.ids, c));
            let rd = Vec3x8::splat(q.r)
                - Vec3x8 {
                    x: ld(&rc.x, c),
                    y: ld(&rc.y, c),
                    z: ld(&rc.z, c),
                };
            let near = (rd.x * rd.x + rd.y * rd.y + rd.z * rd.z).simd_le(F32s::splat(k.s2)).to_bitmask();
            let same = u32x8::from(ld_idx(&rc.cloth, c)).simd_eq(u32x8::splat(q.cloth)).to_bitmask();
            bits &= !(near & same) & !ids.simd_eq(u32x8::splat(q.i)).to_bitmask();
            if bits != 0 {
                emit_lanes(buf, ids, q.i, bits);
            }
            c += LANES;
        }
    }
}

/// Appends `(min(i, j), max(i, j))` for the id `j` of each lane set in `bits`, in lane order
/// (as the scalar scan does). Every lane's pair is written and the end advances past the kept
/// ones only, so there is no branch a lane: which lanes are kept does not follow a pattern the
/// branch predictor could learn.
#[inline(always)]
fn emit_lanes(buf: &mut Vec<u32>, ids: u32x8, i: u32, bits: u32) {
    let qi = u32x8::splat(i);
    let (lo, hi) = (ids.min(qi).to_array(), ids.max(qi).to_array());
    buf.reserve(2 * LANES);
    let len = buf.len();
    let spare = &mut buf.spare_capacity_mut()[..2 * LANES];
    let mut n = 0;
    for l in 0..LANES {
        // SAFETY: `n <= 2 l` before lane `l`, so `n + 1 < 2 LANES = spare.len()` (checked
        // indexing costs 1-2% on the suite's piles).
        unsafe {
            spare.get_unchecked_mut(n).write(lo[l]);
            spare.get_unchecked_mut(n + 1).write(hi[l]);
        }
        n += 2 * ((bits >> l) & 1) as usize;
    }
    // SAFETY: the first `n` spare places were written above (`n <= 2 LANES`, within the
    // reserve).
    unsafe { buf.set_len(len + n) };
}
