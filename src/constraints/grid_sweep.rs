//! The structured sweep of grid colours ([`grid`](super::grid)): one pass over a grid's band
//! colours or its seam colours, a task per band or seam, row by row.

use std::sync::atomic::{AtomicU8, AtomicUsize, Ordering};

use rayon::prelude::*;

use crate::constraints::distance::Colour;
use crate::constraints::grid::GridColour;
use crate::constraints::grid_row::row;
use crate::data::lanes::{SharedVec3, LANES};

/// A pass's constraints below which it runs on one thread: a fork and join costs more than the
/// second thread saves.
pub const SERIAL_MAX: usize = 16_384;

/// Most colours one pass holds: the twelve classes.
const MAX_COLOURS: usize = 12;

/// A colour's multipliers as a raw view: the tasks of a pass write disjoint rows of it.
#[derive(Clone, Copy)]
pub(crate) struct Multipliers {
    ptr: *mut f32,
    len: usize,
}

// SAFETY: a pointer and a length; rows are handed to one task each (see `row`).
unsafe impl Send for Multipliers {}
// SAFETY: as above.
unsafe impl Sync for Multipliers {}

impl Multipliers {
    const EMPTY: Multipliers = Multipliers {
        ptr: std::ptr::null_mut(),
        len: 0,
    };

    fn new(lambda: &mut [f32]) -> Self {
        Multipliers {
            ptr: lambda.as_mut_ptr(),
            len: lambda.len(),
        }
    }

    /// Row `k` of `per_row` multipliers.
    ///
    /// # Safety
    /// No other live reference covers this row (each row belongs to one task of a pass), and
    /// the slice is dropped before the pass ends (the colour outlives the pass).
    pub(crate) unsafe fn row<'a>(self, k: u32, per_row: u32) -> &'a mut [f32] {
        let (s, n) = (k as usize * per_row as usize, per_row as usize);
        assert!(s + n <= self.len);
        // SAFETY: in bounds (checked above) and exclusive by the caller's guarantee.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(s), n) }
    }
}

/// Per-sweep settings shared by every row.
#[derive(Clone, Copy)]
pub(crate) struct Sweep<'a> {
    pub p: SharedVec3,
    pub w: &'a [f32],
    pub inv_h2: f32,
}

/// One pass over colours of one grid that share their groups (its band colours, or its seam
/// colours): a task per group runs each colour's rows of that group, colour after colour.
/// `RESET`: the multipliers read as zero; `STORE`: they are written.
pub(crate) fn run_pass<const RESET: bool, const STORE: bool>(colours: &mut [Colour], s: &Sweep<'_>, parallel: bool) {
    assert!(colours.iter().all(|c| c.grid.is_some()));
    let lambdas = multipliers(colours);
    let colours: &[Colour] = colours;
    let Some(groups) = colours.first().and_then(|c| c.grid.as_ref()).map(GridColour::group_count) else {
        return;
    };
    // SAFETY: a group's rows hold constraints of that group only; groups (bands, or seams of
    // boundaries at least four rows apart) share no particle, and each multiplier row
    // belongs to one group, so tasks touch disjoint particles and multipliers.
    let task = |q: usize| unsafe { sweep_group::<RESET, STORE>(colours, &lambdas, q, s) };
    let work: usize = colours.iter().map(|c| c.real).sum();
    if parallel && groups > 1 && work > SERIAL_MAX {
        (0..groups).into_par_iter().for_each(task);
    } else {
        (0..groups).for_each(task);
    }
}

/// The multipliers of up to [`MAX_COLOURS`] colours as raw views, in colour order.
fn multipliers(colours: &mut [Colour]) -> [Multipliers; MAX_COLOURS] {
    assert!(colours.len() <= MAX_COLOURS);
    let mut lambdas = [Multipliers::EMPTY; MAX_COLOURS];
    for (m, c) in lambdas.iter_mut().zip(colours.iter_mut()) {
        *m = Multipliers::new(&mut c.lambda);
    }
    lambdas
}

/// Runs each colour's rows of group `q`, colour after colour (`lambdas` from [`multipliers`]).
///
/// # Safety
/// No other task touches the particles or multipliers of group `q`'s rows meanwhile.
unsafe fn sweep_group<const RESET: bool, const STORE: bool>(colours: &[Colour], lambdas: &[Multipliers], q: usize, s: &Sweep<'_>) {
    for (c, lambda) in colours.iter().zip(lambdas) {
        let Some(g) = &c.grid else { continue };
        // `α̃ > 0` makes every denominator positive (inverse masses are finite and not
        // negative), so its rows skip that test; a colour without compliance keeps no
        // multipliers ([`GridColour::keeps_multipliers`]): its rows run as after a reset.
        let positive = g.alpha(s.inv_h2) > 0.0;
        let keeps = g.keeps_multipliers();
        for i in g.group(q) {
            // SAFETY: the caller owns the group's rows.
            unsafe {
                match (positive, keeps) {
                    (true, _) => row::<RESET, STORE, false>(g, i, lambda, s),
                    (false, true) => row::<RESET, STORE, true>(g, i, lambda, s),
                    (false, false) => row::<true, false, true>(g, i, lambda, s),
                }
            }
        }
    }
}

/// Most parts a wave is cut into (see [`run_wave`]).
const MAX_PARTS: usize = 16;

/// What a wave hands the particles to around the sweep (the grid must start at particle 0).
#[derive(Clone, Copy)]
pub(crate) struct Finish<'a> {
    /// The padded particle count (a multiple of eight, covering the grid).
    pub len: usize,
    /// Takes each band's particles (the last band's up to `len`) just before the sweep
    /// reaches the band; requires band edges on whole blocks of eight ([`bands_on_blocks`]).
    pub before: Option<&'a (dyn Fn(std::ops::Range<usize>) + Sync)>,
    /// Takes every particle once, in ranges of whole blocks, once the sweep is done with it.
    pub after: &'a (dyn Fn(std::ops::Range<usize>) + Sync),
}

/// Whether every band of a grid of `cols` columns starts on a whole block of eight particles
/// (the grid starting at particle 0), as [`Finish::before`] requires.
pub(crate) fn bands_on_blocks(cols: u32) -> bool {
    (super::grid::band_rows(cols) as usize * cols as usize).is_multiple_of(LANES)
}

/// One sweep of a grid's band colours and seam colours as a wave. With `finish`, every
/// particle is handed to its `after` (ranges of whole blocks of eight, each particle once) as
/// soon as the sweep is done with it, while the particle is still in cache, and each band to
/// its `before` just before the sweep reaches the band; the particles beyond the grid go with
/// the last band. Without, the wave is just the sweep: each seam runs
/// right after the bands on both its sides, and a pass needs one fork and join where
/// [`run_pass`] over the bands and then over the seams needs two.
///
/// The bands are cut into parts of consecutive bands ([`part_bounds`]: a multiple of the
/// pool's threads, about as many rows in each). A task runs its part band after band: the band's
/// colours, then the seam above it, then finishes the rows that no later constraint of
/// the sweep touches (all but the two rows on each side of a seam still to come). The seam
/// between two parts and the rows around it run as soon as the upper part has finished and
/// the lower part has run its first band, in the task that does the later of the two: after
/// both bands beside it and before nothing else that touches those rows, so the task that
/// runs it changes no bit. A particle meets its
/// constraints in the order of the two passes [`run_pass`] makes (its band's colours, then
/// its seam's), so the bits are those of the two passes followed by `finish` over all
/// particles.
pub(crate) fn run_wave<const RESET: bool, const STORE: bool>(
    bands: &mut [Colour],
    seams: &mut [Colour],
    s: &Sweep<'_>,
    parallel: bool,
    finish: Option<Finish<'_>>,
) {
    let Some(spec) = bands.first().and_then(|c| c.grid.as_ref()).map(|g| g.spec) else {
        if let Some(f) = finish {
            if let Some(before) = f.before {
                before(0..f.len);
            }
            (f.after)(0..f.len);
        }
        return;
    };
    let same = |c: &Colour| c.grid.as_ref().is_some_and(|g| g.spec == spec);
    assert!(bands.iter().chain(seams.iter()).all(same));
    let len = finish.map_or(0, |f| f.len);
    if let Some(f) = finish {
        assert!(spec.first == 0 && len.is_multiple_of(LANES) && (spec.rows * spec.cols) as usize <= len);
        assert!(f.before.is_none() || bands_on_blocks(spec.cols));
    }
    let before = finish.and_then(|f| f.before);
    let finish = |r: std::ops::Range<usize>| {
        if let Some(f) = finish {
            (f.after)(r);
        }
    };
    let (band_l, seam_l) = (multipliers(bands), multipliers(seams));
    let (bands, seams): (&[Colour], &[Colour]) = (bands, seams);
    // SAFETY (the three closures below): as in `run_pass`, a group's rows touch only the
    // particles of that group; a task owns its part's bands, the seams inside its part and
    // the finished ranges of its part, which the seams between parts do not reach (they
    // touch two rows on each side of a boundary); those seams and the rows around them run
    // after all tasks, one boundary a task.
    let group = |colours: &[Colour], lambdas: &[Multipliers], q: usize| unsafe { sweep_group::<RESET, STORE>(colours, lambdas, q, s) };
    let (cols, b) = (spec.cols as usize, super::grid::band_rows(spec.cols) as usize);
    let nb = (spec.rows as usize).div_ceil(b);
    let down = |i: usize| i - i % LANES;
    let up = |i: usize| down(i + LANES - 1).min(len);
    let work: usize = bands.iter().chain(seams.iter()).map(|c| c.real).sum();
    let threads = if parallel && work > SERIAL_MAX {
        rayon::current_num_threads()
    } else {
        1
    };
    let (first, parts) = part_bounds(nb, b, spec.rows as usize, threads);
    // where part `k`'s own finished range starts
    let start = |k: usize| if k == 0 { 0 } else { up((first[k] * b + 2) * cols) };
    // Boundary `k` (above part `k > 0`) is ready when part `k - 1` has finished (its end in
    // `ends`) and part `k` has run its first band; whichever of the two comes second runs its
    // seam and the rows around it, at once, whether the two parts run side by side or one
    // after the other on one thread.
    let arrived: [AtomicU8; MAX_PARTS] = Default::default();
    let ends: [AtomicUsize; MAX_PARTS] = Default::default();
    let fix = |k: usize| {
        group(seams, &seam_l, first[k] - 1);
        let (from, to) = (ends[k - 1].load(Ordering::Acquire), start(k));
        if to > from {
            finish(from..to);
        }
    };
    let arrive = |k: usize| {
        if arrived[k].fetch_add(1, Ordering::AcqRel) == 1 {
            fix(k);
        }
    };
    let run_part = |k: usize| {
        let (q0, q1) = (first[k], first[k + 1]);
        let mut done = start(k);
        for q in q0..q1 {
            if let Some(before) = before {
                before(q * b * cols..if q + 1 == nb { len } else { (q + 1) * b * cols });
            }
            group(bands, &band_l, q);
            if q > q0 {
                group(seams, &seam_l, q - 1);
            }
            let end = if q + 1 == nb { len } else { down(((q + 1) * b - 2) * cols) };
            if end > done {
                finish(done..end);
                done = end;
            }
            if q == q0 && k > 0 {
                arrive(k);
            }
        }
        if k + 1 < parts {
            ends[k].store(done, Ordering::Release);
            arrive(k + 1);
        }
    };
    if parts == 1 {
        run_part(0);
        return;
    }
    (0..parts).into_par_iter().for_each(run_part);
}

/// The first band of each part of a wave over `nb` bands of `b` rows (the last band holds the
/// rest of `rows`) on a pool of `threads`, and the number of parts: a multiple of the threads,
/// about two bands a thread or more, at most [`MAX_PARTS`], with the part boundaries where
/// the rows split most evenly. A part between two others holds two bands or more, so that
/// the seams of its two boundaries and the rows around them stay apart; the first and the
/// last part may hold one. One thread, or one band: one part. Parts only decide which task
/// runs a band; the bits do not depend on them.
fn part_bounds(nb: usize, b: usize, rows: usize, threads: usize) -> ([usize; MAX_PARTS + 1], usize) {
    let mut first = [nb; MAX_PARTS + 1];
    first[0] = 0;
    let most = ((nb + 2) / 2).min(MAX_PARTS);
    if threads < 2 || nb < 2 {
        return (first, 1);
    }
    let t = threads.min(most);
    let parts = (t * (nb / (2 * t)).max(1)).min(most / t * t);
    // bands that parts k.. need: two each, one for the last
    let need = |k: usize| 2 * (parts - k) - 1;
    // part k starts at the band boundary nearest k / parts of the rows, after the bands the
    // previous part needs and early enough to leave the later parts theirs
    for k in 1..parts {
        let want = (k * rows + parts / 2) / parts;
        let q = (want + b / 2) / b;
        let after = first[k - 1] + if k == 1 { 1 } else { 2 };
        first[k] = q.max(after).min(nb - need(k));
    }
    (first, parts)
}

#[cfg(test)]
mod tests {
    use super::{part_bounds, MAX_PARTS};

    /// Parts cover the bands in order, two bands or more each but the first and the last, a
    /// multiple of the threads, and split the rows about evenly: with four bands a part or
    /// more, no part is a band above or below its even share of the rows.
    #[test]
    fn parts_are_whole_bands_a_multiple_of_the_threads_and_even_in_rows() {
        let bounds = |nb, b, rows, t| {
            let (first, parts) = part_bounds(nb, b, rows, t);
            first[..=parts].to_vec()
        };
        assert_eq!(bounds(7, 16, 100, 2), [0, 3, 7]);
        assert_eq!(bounds(3, 16, 40, 2), [0, 1, 3]);
        assert_eq!(bounds(2, 16, 20, 3), [0, 1, 2]);
        for threads in 1..=5 {
            for nb in 1..=70 {
                for b in [4usize, 7, 16] {
                    for last in [1, b] {
                        let rows = (nb - 1) * b + last;
                        let (first, parts) = part_bounds(nb, b, rows, threads);
                        let bands = |k: usize| first[k]..first[k + 1];
                        let rows_of = |k: usize| bands(k).map(|q| if q + 1 == nb { last } else { b }).sum::<usize>();
                        assert_eq!((first[0], first[parts]), (0, nb));
                        if threads == 1 || nb < 2 {
                            assert_eq!(parts, 1);
                            continue;
                        }
                        // as many parts as bands allow when that is fewer than the threads
                        let most = ((nb + 2) / 2).min(MAX_PARTS);
                        assert!(
                            parts <= most
                                && if threads <= most {
                                    parts.is_multiple_of(threads)
                                } else {
                                    parts == most
                                }
                        );
                        let fits = |k: usize| bands(k).len() >= if k == 0 || k + 1 == parts { 1 } else { 2 };
                        assert!((0..parts).all(fits), "{nb} bands, {threads} threads: {first:?}");
                        let share = rows.div_ceil(parts);
                        let largest = (0..parts).map(rows_of).max().unwrap();
                        let smallest = (0..parts).map(rows_of).min().unwrap();
                        // the clamps to two bands a part may leave a part above its share
                        if nb >= 4 * parts {
                            assert!(
                                largest <= share + b && smallest + b >= rows / parts,
                                "{nb} bands of {b}, {threads} threads: {first:?}"
                            );
                        }
                    }
                }
            }
        }
    }
}
