//! The self-collision query of the spatial hash, cell by cell over a half shell: the lists of
//! [`SpatialHash::query_upper_unskipped`] (module `hash_rest`), found with half the distance
//! tests and a ninth of the row look-ups.
//!
//! # Method
//! The particle query scans, for each particle, the 3x3x3 cells around it: 9 rows, each a
//! hashed look-up (the splitmix finalizer) and a lane scan, and every pair is tested twice
//! (once from each side, the `j > i` test dropping one). Here the occupied buckets are walked
//! instead (`cell_entries` is in bucket order). The *home cell* of a bucket is the cell of its
//! first particle; a particle of the bucket is a *member* when it lies in the home cell and its
//! search box `[x - r, x + r]³` (`r` the query's rounding-safe radius) stays within the 27
//! cells around it. For the members of a cell, the neighbour rows of its **half shell** are
//! looked up once:
//!
//! ```text
//! own row (cy, cz):                        the cell's own bucket after the member, and cx + 1
//! rows (cy+1, cz), (cy-1, cz+1), (cy, cz+1), (cy+1, cz+1):  cells cx-1 ..= cx+1
//! ```
//!
//! (13 of the 26 neighbours, one of each opposite pair), and each member is tested against
//! their particles eight at a time with the rule of `hash_rest` (distance, cloth, rest
//! distance, computed operation for operation alike; the two sides of a pair only negate the
//! differences, so the decision is the same whichever side tests). A kept pair is emitted as
//! `(min, max)`. Every pair within reach is found: if both particles are members, their cells
//! are adjacent (a member's neighbours lie in its box, inside the 27 cells) and the one whose
//! half shell holds the other finds it; any other particle (on a cell face, or sharing a bucket
//! with another cell) scans its own full box like the particle query. Hash collisions and
//! those particles can emit a pair twice; the assembly (`neighbours_pairs`: count, prefix sum,
//! scatter, sort each list, drop repeats) makes the lists canonical, equal to the particle
//! query's bit for bit on any number of threads.
//!
//! # Measured
//! `examples/self_collision_timeline` (100x100 fold, basic VcCPBD, 150 steps, one thread,
//! load 5 on two cores, the particle query and this one run alternately, two rounds), ms a
//! step: hash query averaged over the run 0.625 / 0.904 before, 0.423 / 0.460 after; a falling
//! step's query (steps 0-45, averaged) 1.45 / 1.84 before, 0.81 / 0.92 after. The folded
//! rebuilds at reach 5 d (steps 46 and 49) stayed at 8-10 ms: there the cost is the kept
//! pairs (48 a particle), whose assembly the two counting sorts of `neighbours_pairs` cut.
//!
//! `examples/self_query_bench` (same build, both queries alternately, 150 repetitions, min;
//! the VM's speed varies 2x between runs, so compare within a line): step 20 (falling, reach
//! 3 d) particle query 0.66-1.34 ms, cell query 0.27-0.54 (0.41x); step 46 (folded, reach
//! 5 d, 485 103 pairs) 4.4-8.7 ms against 3.4-5.3 (0.6-0.8x).
//!
//! Scanning the member's own bucket and the next cell of its row as one range (they are
//! adjacent in the slots unless the row wraps): falling step 0.504-0.703 -> 0.486-0.666 ms
//! (three alternate pairs). The falling cloth holds 6-7 particles an occupied bucket.
//!
//! Tried and not kept: cells wider than the reach (1.25 and 1.5 times; the half shell needs
//! at least the reach): step 20 cell query 0.64 and 0.96 ms against 0.40-0.54 at 1.0, more
//! candidates a member for the same look-ups. Computing every mask of a block without the
//! branch on the distance mask (the branch is taken about half the time while falling):
//! cell / particle ratio 0.37-0.41 against 0.41-0.42, within the noise, so the simpler
//! branching kernel stays.
//!
//! Session 12: the lane scan loads without bounds checks (the slot arrays are padded by a
//! lane group, so a range ending inside them can be checked once): callgrind over the basic
//! fold's timeline, one thread, step start 573.6 -> 530.1 million instructions; three
//! alternate runs, query column 27.2-27.3 -> 26.5-26.8 ms.
//!
//! Tried in session 11 and not kept (a falling step's query, step 20 of the basic fold,
//! ~7.9 million instructions, ~12 lane groups a member at ~45% lane use; alternate runs of a
//! micro-bench, 500-1000 queries each): each row range cut once into lane-width slices, so
//! the loads need no bounds checks: 333-338 against 285-306 µs (the per-range setup outweighs
//! the checks; a range is ~2.4 groups); the rows of a cell scanned once for a batch of up to
//! eight members (each group loaded once): 158.4 against 158.6 million instructions for 20
//! queries, the same time; the rows copied once a cell into one padded buffer that every
//! member scans in full groups: 365-369 against 301-303 µs (1 468 against 1 391-1 421 at the
//! impact, step 44): the copy costs more than the partial groups it saves.
//!
//! Tried in session 13 and not kept: the members of a cell in the lanes (up to eight, loaded
//! once) and each candidate of the half shell broadcast against them, one lane group a
//! candidate for the whole cell. Most candidates of a cloth lie within reach of some member,
//! so nearly every one also ran the rest test; callgrind of 20 falling-step queries 754 ->
//! 821 million instructions, and in the timeline (three alternate runs) the query column
//! 24.5-25.9 -> 26.0-27.7 ms, slower at every falling step, although a warm-cache micro-bench
//! had it 3-10% faster.

use crate::data::lanes::{load, load_idx, load_idx_unchecked, load_unchecked, F32s, Vec3x8, LANES};
use crate::self_collision::hash::SpatialHash;
use crate::self_collision::neighbours::{search_radius, within, Neighbours};
use crate::Result;
use wide::u32x8;

mod members;

/// Buckets walked by one parallel task (fixed, so the split does not depend on the threads).
const BUCKETS_PER_TASK: usize = 1024;

/// The half-shell rows other than the cell's own, as `(dy, dz)`; each is read over
/// `cx - 1 ..= cx + 1`.
const ROWS: [(i32, i32); 4] = [(1, 0), (-1, 1), (0, 1), (1, 1)];

/// One particle's data for the scans.
struct Probe {
    i: u32,
    p: [f32; 3],
    r: [f32; 3],
    cloth: u32,
}

/// The query's constants.
#[derive(Clone, Copy)]
struct Reach {
    md2: f32,
    r: f32,
    s2: f32,
    /// The shortest of the slot arrays the lane scan reads (positions and rest data, each
    /// padded by a lane group): a range ending at `e` with `e + LANES <= len` is scanned
    /// without bounds checks.
    len: usize,
}

impl SpatialHash {
    /// Same lists as [`SpatialHash::query_upper_unskipped`] (each pair once under its smaller
    /// id, within `max_dist`, rest neighbours within `skip` dropped), found cell by cell over
    /// a half shell (see the module docs); parallel over fixed groups of buckets.
    ///
    /// Errors like [`SpatialHash::query_upper_unskipped`].
    pub fn query_upper_unskipped_cells(&self, max_dist: f32, skip: f32, out: &mut Neighbours) -> Result<()> {
        let (md2, s2) = self.check_rest_query(max_dist, skip)?;
        let k = Reach {
            md2,
            r: search_radius(max_dist),
            s2,
            len: self.scan_len(),
        };
        let ts = self.table_size;
        out.fill_pairs_parallel(self.n, ts.div_ceil(BUCKETS_PER_TASK), |t, buf| {
            let end = ((t + 1) * BUCKETS_PER_TASK).min(ts);
            for b in t * BUCKETS_PER_TASK..end {
                self.bucket_pairs::<true>(b, k, buf);
            }
        })
    }

    /// Serial, scalar twin of [`SpatialHash::query_upper_unskipped_cells`]; identical lists.
    pub fn query_upper_unskipped_cells_serial(&self, max_dist: f32, skip: f32, out: &mut Neighbours) -> Result<()> {
        let (md2, s2) = self.check_rest_query(max_dist, skip)?;
        let k = Reach {
            md2,
            r: search_radius(max_dist),
            s2,
            len: self.scan_len(),
        };
        out.fill_pairs_serial(self.n, |buf| {
            for b in 0..self.table_size {
                self.bucket_pairs::<false>(b, k, buf);
            }
        })
    }

    /// The shortest of the slot arrays [`SpatialHash::pair_scan_lanes`] reads.
    fn scan_len(&self) -> usize {
        let rc = &self.rest;
        [
            self.sx.len(),
            self.sy.len(),
            self.sz.len(),
            rc.x.len(),
            rc.y.len(),
            rc.z.len(),
            rc.ids.len(),
            rc.cloth.len(),
        ]
        .into_iter()
        .min()
        .unwrap_or(0)
    }

    /// The probe of the particle in slot `k`.
    #[inline(always)]
    fn probe_of(&self, k: usize) -> Probe {
        let rc = &self.rest;
        Probe {
            i: rc.ids[k],
            p: [self.sx[k], self.sy[k], self.sz[k]],
            r: [rc.x[k], rc.y[k], rc.z[k]],
            cloth: rc.cloth[k],
        }
    }

    /// Emits the kept pairs of the particles of bucket `b` (see the module docs).
    #[inline]
    fn bucket_pairs<const SIMD: bool>(&self, b: usize, k: Reach, buf: &mut Vec<u32>) {
        let (s, e) = (self.cell_start[b] as usize, self.cell_start[b + 1] as usize);
        if s == e {
            return;
        }
        let home = self.cell_of_slot(s);
        let mut ranges = [(0usize, 0usize); 9];
        let mut nr = 0;
        let mut members = 0u32;
        for slot in s..e {
            let is_member = if SIMD {
                if (slot - s) % LANES == 0 {
                    members = self.member_lanes(slot, e, home, k.r);
                }
                members & (1 << ((slot - s) % LANES)) != 0
            } else {
                self.member(slot, home, k.r)
            };
            if !is_member {
                self.full_box::<SIMD>(slot, k, buf);
                continue;
            }
            if nr == 0 {
                nr = self.half_shell(b, home, &mut ranges);
            }
            let q = self.probe_of(slot);
            // Bucket `b + 1` (the next cell of the row) follows bucket `b` in the slots unless
            // the row wraps past the table's end: then one range covers both.
            let merged = b + 1 < self.table_size;
            let own_end = if merged { self.cell_start[b + 2] as usize } else { e };
            self.pair_scan::<SIMD>(&q, k, slot + 1, own_end, buf);
            for &(rs, re) in &ranges[usize::from(merged)..nr] {
                self.pair_scan::<SIMD>(&q, k, rs, re, buf);
            }
        }
    }

    /// The slot ranges of the half shell of cell `home` (bucket `b`) other than its own
    /// bucket: the next cell of the own row (the next bucket), then each other row's three
    /// buckets (two ranges when they wrap past the table's end). Returns how many.
    fn half_shell(&self, b: usize, home: [i32; 3], ranges: &mut [(usize, usize); 9]) -> usize {
        let ts = self.table_size;
        let mask = ts - 1;
        let nb = (b + 1) & mask;
        ranges[0] = (self.cell_start[nb] as usize, self.cell_start[nb + 1] as usize);
        let mut nr = 1;
        for (dy, dz) in ROWS {
            let base = self.row_base(home[1].wrapping_add(dy), home[2].wrapping_add(dz));
            let b0 = (base.wrapping_add(i64::from(home[0]) as u64).wrapping_sub(1) & mask as u64) as usize;
            let b1 = b0 + 3;
            if b1 <= ts {
                ranges[nr] = (self.cell_start[b0] as usize, self.cell_start[b1] as usize);
                nr += 1;
            } else {
                ranges[nr] = (self.cell_start[b0] as usize, self.cell_start[ts] as usize);
                ranges[nr + 1] = (0, self.cell_start[b1 - ts] as usize);
                nr += 2;
            }
        }
        nr
    }

    /// Scans the whole search box of the particle in slot `k` (a non-member).
    fn full_box<const SIMD: bool>(&self, k: usize, kr: Reach, buf: &mut Vec<u32>) {
        let q = self.probe_of(k);
        let boxed = self.box_ranges(q.p, kr.r, |b0, b1| {
            let (s, e) = (self.cell_start[b0] as usize, self.cell_start[b1] as usize);
            self.pair_scan::<SIMD>(&q, kr, s, e, buf);
        });
        if !boxed {
            self.pair_scan::<SIMD>(&q, kr, 0, self.cell_entries.len(), buf);
        }
    }

    /// Emits `(min, max)` for each kept partner of `q` among slots `s..e` (itself excluded).
    #[inline(always)]
    fn pair_scan<const SIMD: bool>(&self, q: &Probe, k: Reach, s: usize, e: usize, buf: &mut Vec<u32>) {
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
        rc.ids[c] != q.i
            && within(q.p[0], q.p[1], q.p[2], self.sx[c], self.sy[c], self.sz[c], k.md2)
            && !(rc.cloth[c] == q.cloth && dx * dx + dy * dy + dz * dz <= k.s2)
    }

    /// Every particle `j != i` of the last build within `max_dist` of the point `p` (not
    /// necessarily particle `i`'s position at the build) that is not a rest neighbour of
    /// `i` (same cloth `cloth`, rest distance to `rest` at most `skip`): the rule of the
    /// self-collision query for one particle, on both sides of it, with the same operations
    /// (a pair decides alike whichever side tests it). Calls `emit(j)` for each, in slot
    /// order, and returns `false`, calling nothing, when `p`'s search box spans more than four
    /// cells an axis (a point far off the build's scale) or no rest data is attached. `p`
    /// must be finite.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn probe_unskipped(
        &self,
        i: u32,
        p: [f32; 3],
        rest: [f32; 3],
        cloth: u32,
        max_dist: f32,
        skip: f32,
        mut emit: impl FnMut(u32),
    ) -> bool {
        if !self.rest.valid {
            return false;
        }
        let q = Probe { i, p, r: rest, cloth };
        let k = Reach {
            md2: max_dist * max_dist,
            r: search_radius(max_dist),
            s2: skip * skip,
            len: self.scan_len(),
        };
        self.box_ranges(p, k.r, |b0, b1| {
            for c in self.cell_start[b0] as usize..self.cell_start[b1] as usize {
                if self.kept(&q, k, c) {
                    emit(self.rest.ids[c]);
                }
            }
        })
    }

    /// Slots `s..e` eight at a time: distance, then (for lanes within reach) identity, cloth
    /// and rest distance, each computed like [`SpatialHash::pair_scan_scalar`] (no FMA).
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
        let mut c = s;
        while c < e {
            let d = Vec3x8 {
                x: ld(&self.sx, c),
                y: ld(&self.sy, c),
                z: ld(&self.sz, c),
            } - pv;
            let mut bits = (d.x * d.x + d.y * d.y + d.z * d.z).simd_le(m2).to_bitmask();
            if e - c < LANES {
                bits &= (1u32 << (e - c)) - 1;
            }
            if bits != 0 {
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
                while bits != 0 {
                    let j = rc.ids[c + bits.trailing_zeros() as usize];
                    buf.extend([q.i.min(j), q.i.max(j)]);
                    bits &= bits - 1;
                }
            }
            c += LANES;
        }
    }
}

#[cfg(test)]
mod tests;
