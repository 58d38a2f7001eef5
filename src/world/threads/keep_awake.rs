//! Keeps a thread pool's other workers polling for work through the serial parts of a step.
//!
//! A step is a chain of short parallel passes (predict, clamp, constraint sweeps, the
//! self-collision pair pass and correction, update) with short serial parts between them. A
//! rayon worker that finds no work for a few microseconds goes to sleep, and the next pass
//! pays for waking it: on a two-thread pool, a wake-up after a serial gap of 20 µs or more
//! added 15-40 µs to a pass of about 20 µs. With the other workers polling instead (they take
//! and run pending work with `rayon::yield_now` and otherwise spin) the pass starts at once.
//!
//! [`run`] does this for the length of one call: the pollers are the other halves of
//! `rayon::join`s (no allocation: the steady-state step allocates nothing), they only run
//! jobs the pool would run anyway, so results do not change (the kernels split their work
//! into fixed chunks; the thread-count tests hold the bits), and they stop when the call
//! returns or unwinds. They cost CPU time on the other cores for that long. Outside a pool,
//! or on a pool of one thread, the call just runs. On a pool shared with other work (the
//! global pool with `threads = 0`), a poller may pick up an unrelated job, and the step then
//! returns when that job is done, as a rayon join that steals work while it waits does.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// What the caller shares with its pollers. It lives on the caller's stack, beside the step's
/// own locals; aligned and sized to two cache lines so that none of them shares its line: the
/// pollers read `stop` in a loop, and a local written on that line would wait for the line on
/// every store (false sharing).
#[derive(Debug, Default)]
#[repr(align(128))]
struct Shared {
    stop: AtomicBool,
    /// Pollers running now.
    running: AtomicUsize,
}

// The flag has its lines to itself, whatever the build's stack layout.
const _: () = assert!(std::mem::align_of::<Shared>() == 128 && std::mem::size_of::<Shared>() == 128);

/// Sets the stop flag when dropped (when the call returns or unwinds).
struct StopOnDrop<'a>(&'a AtomicBool);

impl Drop for StopOnDrop<'_> {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Release);
    }
}

/// Runs `f` while the other workers of the pool the caller runs in poll for work (see the
/// module docs); just runs `f` outside a pool or on a pool of one thread.
pub(crate) fn run<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    run_with(&Shared::default(), f)
}

fn run_with<R: Send>(sh: &Shared, f: impl FnOnce() -> R + Send) -> R {
    match rayon::current_thread_index() {
        Some(me) if rayon::current_num_threads() > 1 => with_pollers(rayon::current_num_threads() - 1, me, sh, f),
        _ => f(),
    }
}

/// Offers `k` pollers for stealing (nested joins, stack-allocated jobs), then runs `f`.
fn with_pollers<R: Send>(k: usize, me: usize, sh: &Shared, f: impl FnOnce() -> R + Send) -> R {
    if k == 0 {
        let _stop = StopOnDrop(&sh.stop);
        return f();
    }
    rayon::join(|| with_pollers(k - 1, me, sh, f), || poll(me, sh)).0
}

/// Runs pending work of the pool until the stop flag is set.
fn poll(me: usize, sh: &Shared) {
    // The caller's own thread may pick its poller up while it waits in a join: it must not
    // spin there (it would never get back to set the flag).
    if rayon::current_thread_index() == Some(me) {
        return;
    }
    sh.running.fetch_add(1, Ordering::AcqRel);
    while !sh.stop.load(Ordering::Acquire) {
        if rayon::yield_now() != Some(rayon::Yield::Executed) {
            std::hint::spin_loop();
        }
    }
    sh.running.fetch_sub(1, Ordering::AcqRel);
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;
    use std::time::{Duration, Instant};

    #[test]
    fn pollers_run_the_pools_work_and_stop_with_the_call() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
        let sh = Shared::default();
        let (sums, seen) = pool.install(|| {
            run_with(&sh, || {
                // A liveness bound, not a timing check: a poller is stolen and starts.
                let t = Instant::now();
                while sh.running.load(Ordering::Acquire) == 0 && t.elapsed() < Duration::from_secs(20) {
                    std::thread::sleep(Duration::from_micros(100));
                }
                let seen = sh.running.load(Ordering::Acquire);
                let mut sums = Vec::new();
                for round in 0..50u64 {
                    // Serial gaps between parallel passes, as in a step.
                    std::thread::sleep(Duration::from_micros(50));
                    sums.push((0..10_000u64).into_par_iter().map(|i| i * round).sum::<u64>());
                }
                (sums, seen)
            })
        });
        assert!((1..=2).contains(&seen), "{seen} pollers running");
        let want: Vec<u64> = (0..50u64).map(|r| (0..10_000u64).map(|i| i * r).sum()).collect();
        assert_eq!(sums, want);
        // The call returns only once its pollers have: none left, the pool free again.
        assert_eq!(sh.running.load(Ordering::Acquire), 0);
        assert!(sh.stop.load(Ordering::Acquire));
        assert_eq!(pool.install(|| (0..100u32).into_par_iter().sum::<u32>()), 4950);
    }

    #[test]
    fn a_panic_in_the_call_stops_the_pollers() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let sh = Shared::default();
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            pool.install(|| run_with(&sh, || panic!("inside the step")))
        }));
        assert!(r.is_err());
        assert!(sh.stop.load(Ordering::Acquire));
        assert_eq!(sh.running.load(Ordering::Acquire), 0);
    }

    #[test]
    fn outside_a_pool_or_on_one_thread_the_call_just_runs() {
        let sh = Shared::default();
        assert_eq!(run_with(&sh, || 7), 7);
        assert!(!sh.stop.load(Ordering::Acquire), "no pollers were set up");
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        assert_eq!(one.install(|| run_with(&sh, || (0..1000u32).into_par_iter().sum::<u32>())), 499_500);
        assert!(!sh.stop.load(Ordering::Acquire));
    }
}
