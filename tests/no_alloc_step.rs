//! Contract: after the first step of a scene whose topology does not change, `World::step`
//! allocates nothing. A counting global allocator counts every allocation (on any thread) while
//! a flag is up.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

use weft::{Backend, ClothDesc, Effects, Fabric, PinSpec, SolverParams, Wind, World};

struct Counting;

static COUNTING: AtomicBool = AtomicBool::new(false);
static ALLOCS: AtomicUsize = AtomicUsize::new(0);
static SITES: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());

thread_local! {
    static INSIDE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Records where an allocation came from (the backtrace's own allocations are not counted).
fn record() {
    ALLOCS.fetch_add(1, Ordering::Relaxed);
    if INSIDE.with(|i| i.replace(true)) {
        return;
    }
    let bt = std::backtrace::Backtrace::force_capture().to_string();
    SITES.lock().unwrap().push(bt);
    INSIDE.with(|i| i.set(false));
}

// SAFETY: forwards to the system allocator; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) && !INSIDE.with(|i| i.get()) {
            record();
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) && !INSIDE.with(|i| i.get()) {
            record();
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(p, l, n) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made while `f` runs.
fn count(f: impl FnOnce()) -> usize {
    ALLOCS.store(0, Ordering::SeqCst);
    SITES.lock().unwrap().clear();
    COUNTING.store(true, Ordering::SeqCst);
    f();
    COUNTING.store(false, Ordering::SeqCst);
    ALLOCS.load(Ordering::SeqCst)
}

fn world(rows: u32, params: SolverParams) -> World {
    let effects = Effects {
        gravity: Some([0.0, -9.81, 0.0]),
        drag: Some(0.01),
        wind: Some(Wind {
            velocity: [2.0, 0.0, 3.0],
            gust: 0.3,
            ..Wind::default()
        }),
    };
    let mut w = World::new(params, effects).unwrap();
    w.add_cloth(&ClothDesc {
        rows,
        cols: rows,
        spacing: 0.02,
        fabric: Fabric::preset("wool").unwrap(),
        pins: vec![PinSpec::FirstRowCorners],
        ..Default::default()
    })
    .unwrap();
    w
}

const STEPS: usize = 200;

/// Allocations in `STEPS` frames after a warm-up, each frame moving a pin, stepping (through
/// `step` and `advance`) and reading positions, normals and interpolated positions into
/// caller buffers. Also returns the backtraces of the allocations.
fn allocs_in_frames(w: &mut World) -> (usize, Vec<String>) {
    let dt = w.params().dt;
    let n = w.particle_count();
    let mut pos = vec![[0.0f32; 3]; n];
    let mut nrm = vec![0.0f32; 3 * n];
    let mut frame = |w: &mut World, k: usize| {
        let mut p = w.position(0).unwrap();
        p.x += 1e-4 * (k as f32).sin();
        w.set_pin_position(0, p).unwrap();
        if k.is_multiple_of(2) {
            w.step(dt).unwrap();
        } else {
            w.advance(dt as f64 * 1.01).unwrap();
        }
        w.read_positions(&mut pos[..]).unwrap();
        w.read_normals(&mut nrm[..]).unwrap();
        w.interpolated_positions(0.5, &mut pos[..]).unwrap();
    };
    for k in 0..4 {
        frame(w, k);
    }
    // Let pool threads finish starting (their start-up allocations are not the step's).
    std::thread::sleep(std::time::Duration::from_millis(50));
    let c = count(|| {
        for k in 4..4 + STEPS {
            frame(w, k);
        }
    });
    (c, SITES.lock().unwrap().clone())
}

fn params(threads: usize) -> SolverParams {
    SolverParams {
        threads,
        ..Default::default()
    }
}

/// Runs every scenario in one test so no other test thread allocates while counting.
#[test]
fn step_does_not_allocate_after_the_first() {
    for rows in [20u32, 80] {
        // 80 x 80 = 6400 particles: the parallel paths (chunks > 4096) run.
        let mut w = world(rows, params(0));
        w.set_caller_thread_only(true);
        assert_eq!(allocs_in_frames(&mut w).0, 0, "caller thread only, {rows} rows");
        let mut w = world(
            rows,
            SolverParams {
                backend: Backend::Scalar,
                ..params(0)
            },
        );
        assert_eq!(allocs_in_frames(&mut w).0, 0, "scalar backend, {rows} rows");

        // Driven from inside the pool that runs it: no job is injected, nothing allocates.
        let pool = Arc::new(rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap());
        let mut w = world(rows, params(0));
        w.set_thread_pool(pool.clone());
        let c = pool.install(|| allocs_in_frames(&mut w).0);
        assert_eq!(c, 0, "stepped from inside its pool, {rows} rows");

        // Entering a pool from outside: weft injects one job per step; rayon's injector queue
        // (crossbeam_deque::Injector::push) allocates one block per 63 injected jobs. That is
        // rayon's machinery, not weft's: every allocation seen must come from there.
        let cases: [(&str, World); 4] = [
            ("own pool, threads = 1", world(rows, params(1))),
            ("own pool, threads = 2", world(rows, params(2))),
            ("global pool", world(rows, params(0))),
            ("caller's pool", {
                let mut w = world(rows, params(0));
                w.set_thread_pool(pool.clone());
                w
            }),
        ];
        for (what, mut w) in cases {
            let (c, sites) = allocs_in_frames(&mut w);
            let injected = STEPS + STEPS / 2; // one per step; advance takes 0, 1 or 2 steps
            assert!(c <= injected.div_ceil(63) + 1, "{what}, {rows} rows: {c} allocations");
            for s in sites.iter().filter(|s| s.contains("record")) {
                assert!(
                    s.contains("Injector") && s.contains("push"),
                    "{what}, {rows} rows: allocation outside rayon's injector:\n{s}"
                );
            }
        }
    }
}
