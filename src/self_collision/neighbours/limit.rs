//! The bound on the entries a fill of [`Neighbours`](super::Neighbours) may write
//! ([`Neighbours::set_limit`](super::Neighbours::set_limit)): particles that have collapsed onto
//! each other, or a reach far above their spacing, would otherwise list every pair (`n²`
//! entries). A fill that passes the limit stops writing, empties the lists and returns
//! [`too_many`]'s error. Its tasks count what they write in batches of [`METER_BATCH`] entries
//! on a [`Meter`] (the shared [`Budget`] is touched once a batch), so what it wrote beyond the
//! limit is at most a batch and one particle's list a running task.

use crate::WeftError;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The entries a fill has written so far, shared by its tasks, against the lists' limit.
pub(crate) struct Budget {
    used: AtomicUsize,
    limit: usize,
}

impl Budget {
    pub(crate) fn new(limit: usize) -> Self {
        Budget {
            used: AtomicUsize::new(0),
            limit,
        }
    }

    /// Counts `k` more entries; `false` once the total passes the limit (the writer stops).
    #[inline]
    pub(crate) fn spend(&self, k: usize) -> bool {
        k == 0 || self.used.fetch_add(k, Ordering::Relaxed).saturating_add(k) <= self.limit
    }

    /// Whether the total has passed the limit.
    #[inline]
    pub(crate) fn over(&self) -> bool {
        self.used.load(Ordering::Relaxed) > self.limit
    }

    /// A task's meter on this budget.
    pub(crate) fn meter(&self) -> Meter<'_> {
        Meter { budget: self, pending: 0 }
    }
}

/// Entries a task counts before it adds them to the shared budget: the tasks touch the
/// shared count once per this many entries, not once per particle.
pub(crate) const METER_BATCH: usize = 1024;

/// One task's count of the entries it wrote, added to its [`Budget`] in batches. The fills
/// hand one to each task and flush it when the task ends (so the budget's total is exact).
pub(crate) struct Meter<'a> {
    budget: &'a Budget,
    pending: usize,
}

impl Meter<'_> {
    /// Counts `k` more entries; `false` once the budget's total passes the limit.
    #[inline]
    pub(crate) fn add(&mut self, k: usize) -> bool {
        self.pending += k;
        self.pending < METER_BATCH || self.flush()
    }

    /// Adds the pending count to the budget; `false` once its total passes the limit.
    pub(crate) fn flush(&mut self) -> bool {
        let k = std::mem::take(&mut self.pending);
        self.budget.spend(k)
    }
}

/// Most entries of any lists: ids and offsets are `u32`.
pub(crate) const MAX_ENTRIES: usize = u32::MAX as usize;

/// The error of a fill past `limit` entries for `n` particles (cold and out of line: the fills'
/// loops stay small enough to inline their callbacks).
#[cold]
#[inline(never)]
pub(crate) fn too_many(limit: usize, n: usize) -> WeftError {
    WeftError::param(
        "max_dist",
        "too large",
        format!(
            "more than {limit} neighbour entries in total ({:.0} a particle): the reach is too large for the particles' spacing, or they have collapsed onto each other",
            limit as f64 / n.max(1) as f64
        ),
    )
}
