//! The self-collision query of the spatial hash, cell by cell over a half shell: each pair
//! once, rest neighbours dropped (the rule of module `hash::rest`), found with half the
//! distance tests and a ninth of the row look-ups of a query particle by particle.
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
//! their particles eight at a time with the rule of `hash::rest` (distance, cloth, rest
//! distance, computed operation for operation alike; the two sides of a pair only negate the
//! differences, so the decision is the same whichever side tests). A kept pair is emitted as
//! `(min, max)`. Every pair within reach is found: if both particles are members, their cells
//! are adjacent (a member's neighbours lie in its box, inside the 27 cells) and the one whose
//! half shell holds the other finds it; any other particle (on a cell face, or sharing a bucket
//! with another cell) scans its own full box like the particle query. Hash collisions and
//! those particles can emit a pair twice; the assembly (`neighbours::pairs`: count, prefix sum,
//! scatter, sort each list, drop repeats) makes the lists canonical, equal to the particle
//! query's bit for bit on any number of threads.
//!
//! # Choices
//! The member's own bucket and the next cell of its row are scanned as one range (they are
//! adjacent in the slots unless the row wraps). Cells are as wide as the reach (the half shell
//! needs at least that; wider cells only add candidates). The lane scan loads without bounds
//! checks: the slot arrays are padded by a lane group, so a range ending inside them is
//! checked once. The members are tested one at a time against lane groups of candidates;
//! putting a cell's members in the lanes instead made every candidate run the rest test.

use crate::data::exec::Exec;
use crate::data::lanes::LANES;
use crate::self_collision::hash::SpatialHash;
use crate::self_collision::neighbours::{search_radius, Meter, Neighbours};
use crate::{Result, WeftError};

mod members;
mod scan;

/// Particles (slots) whose buckets one parallel task walks. The tasks cut the slots, not the
/// buckets: a scene's occupied buckets can crowd into a few stretches of the table (a pile
/// under the linear row map), and equal runs of buckets then left one task most of the work.
/// The cut is a function of the build alone, not of the threads (and the lists are canonical
/// whatever the split).
const SLOTS_PER_TASK: usize = 512;

/// The half-shell rows other than the cell's own, as `(dy, dz)`; each is read over
/// `cx - 1 ..= cx + 1`.
const ROWS: [(i32, i32); 4] = [(1, 0), (-1, 1), (0, 1), (1, 1)];

/// One particle's data for the scans.
struct Probe {
    i: u32,
    p: [f32; 3],
    r: [f32; 3],
    cloth: u32,
    /// Its travel (zero when none is attached).
    t: f32,
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
    /// The collision distance when the particles' travels are attached: each pair is then
    /// kept within its own reach (`pair_reach2`), not `md2`.
    own: Option<f32>,
}

impl SpatialHash {
    /// The self-collision lists (each pair once under its smaller id, within `max_dist`, rest
    /// neighbours within `skip` dropped), found cell by cell over a half shell (see the module
    /// docs); parallel over tasks of 512 particles' buckets (`SLOTS_PER_TASK`).
    ///
    /// Errors if `max_dist` or `skip` is negative or non-finite, `max_dist` exceeds the
    /// spacing, or no rest data was attached since the last build.
    pub fn query_upper_unskipped_cells(&self, max_dist: f32, skip: f32, out: &mut Neighbours) -> Result<()> {
        let k = self.reach(max_dist, skip)?;
        let tasks = self.cell_entries.len().div_ceil(SLOTS_PER_TASK).max(1);
        out.fill_pairs_parallel(self.n, tasks, |t, buf, meter| {
            for b in self.task_buckets(t, tasks) {
                if !self.bucket_pairs::<true>(b, k, buf, meter) {
                    return;
                }
            }
        })
    }

    /// The buckets task `t` of `tasks` walks: those whose first slot lies in the task's
    /// [`SLOTS_PER_TASK`] slots (the last task also takes the empty buckets at the end), so
    /// every bucket falls to one task.
    fn task_buckets(&self, t: usize, tasks: usize) -> std::ops::Range<usize> {
        let ts = self.table_size;
        let starts = &self.cell_start[..ts];
        let first = |t: usize| starts.partition_point(|&s| (s as usize) < t * SLOTS_PER_TASK);
        first(t)..if t + 1 >= tasks { ts } else { first(t + 1) }
    }

    /// [`SpatialHash::query_upper_unskipped_cells`] when `exec` is parallel, else a serial walk
    /// with the lanes of `exec` (never entering rayon); identical lists.
    pub(crate) fn query_upper_unskipped_cells_exec(&self, max_dist: f32, skip: f32, out: &mut Neighbours, exec: Exec) -> Result<()> {
        match (exec.parallel(), exec.simd()) {
            (true, _) => self.query_upper_unskipped_cells(max_dist, skip, out),
            (false, true) => self.cells_serial::<true>(max_dist, skip, out),
            (false, false) => self.cells_serial::<false>(max_dist, skip, out),
        }
    }

    /// Serial, scalar twin of [`SpatialHash::query_upper_unskipped_cells`]; identical lists.
    pub fn query_upper_unskipped_cells_serial(&self, max_dist: f32, skip: f32, out: &mut Neighbours) -> Result<()> {
        self.cells_serial::<false>(max_dist, skip, out)
    }

    /// The serial walk over every bucket, with or without lanes.
    fn cells_serial<const SIMD: bool>(&self, max_dist: f32, skip: f32, out: &mut Neighbours) -> Result<()> {
        let k = self.reach(max_dist, skip)?;
        out.fill_pairs_serial(self.n, |buf, meter| {
            for b in 0..self.table_size {
                if !self.bucket_pairs::<SIMD>(b, k, buf, meter) {
                    return;
                }
            }
        })
    }

    /// The query's constants, after checking the arguments (with travels attached, `max_dist`
    /// must cover the members' largest reach `d + 2 t d`, `t` the smaller of the members'
    /// travel and the largest).
    fn reach(&self, max_dist: f32, skip: f32) -> Result<Reach> {
        let (md2, s2) = self.check_rest_query(max_dist, skip)?;
        let rc = &self.rest;
        if let Some(d) = rc.d {
            let t = rc.cell.min(rc.top);
            let members = d + (t + t) * d;
            if max_dist < members {
                return Err(WeftError::param(
                    "max_dist",
                    max_dist,
                    format!("must cover the reach of the cells' members ({members})"),
                ));
            }
        }
        Ok(Reach {
            md2,
            r: search_radius(max_dist),
            s2,
            len: self.scan_len(),
            own: rc.d,
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
            if rc.d.is_some() { rc.travel.len() } else { usize::MAX },
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
            t: if rc.d.is_some() { rc.travel[k] } else { 0.0 },
        }
    }

    /// Emits the kept pairs of the particles of bucket `b` (see the module docs), counting
    /// each particle's on the task's `meter`; `false` when the lists' limit is passed (the
    /// query stops).
    #[inline]
    fn bucket_pairs<const SIMD: bool>(&self, b: usize, k: Reach, buf: &mut Vec<u32>, meter: &mut Meter<'_>) -> bool {
        let (s, e) = (self.cell_start[b] as usize, self.cell_start[b + 1] as usize);
        if s == e {
            return true;
        }
        let home = self.cell_of_slot(s);
        let mut ranges = [(0usize, 0usize); 9];
        let mut nr = 0;
        let mut members = 0u32;
        for slot in s..e {
            let before = buf.len();
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
                if !meter.add((buf.len() - before) / 2) {
                    return false;
                }
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
            if !meter.add((buf.len() - before) / 2) {
                return false;
            }
        }
        true
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
        let rc = &self.rest;
        // A particle faster than the cells' members reaches every partner within
        // `d + (t + t_max) d`.
        let r = match rc.d {
            Some(d) if q.t > rc.cell => search_radius(d + (q.t + rc.top) * d),
            _ => kr.r,
        };
        let boxed = self.box_ranges(q.p, r, |b0, b1| {
            let (s, e) = (self.cell_start[b0] as usize, self.cell_start[b1] as usize);
            self.pair_scan::<SIMD>(&q, kr, s, e, buf);
        });
        if !boxed {
            self.pair_scan::<SIMD>(&q, kr, 0, self.cell_entries.len(), buf);
        }
    }
}

#[cfg(test)]
mod tests;
