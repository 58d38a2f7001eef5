//! The memory estimate (`weft::model::budget`) held to allocations measured by a counting
//! global allocator: mid-size worlds are built and stepped, and the peak of the bytes live
//! during that must lie within a factor of two of the estimate computed from the counts.
//!
//! One test in this binary, so no other test's allocations are counted.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(l) };
        if !p.is_null() {
            let now = LIVE.fetch_add(l.size(), Ordering::Relaxed) + l.size();
            PEAK.fetch_max(now, Ordering::Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) };
        LIVE.fetch_sub(l.size(), Ordering::Relaxed);
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(l) };
        if !p.is_null() {
            let now = LIVE.fetch_add(l.size(), Ordering::Relaxed) + l.size();
            PEAK.fetch_max(now, Ordering::Relaxed);
        }
        p
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, new: usize) -> *mut u8 {
        let q = unsafe { System.realloc(p, l, new) };
        if !q.is_null() {
            // Count the old and the new block both live at the moment of the move (an upper
            // bound of what a realloc holds).
            let now = LIVE.fetch_add(new, Ordering::Relaxed) + new;
            PEAK.fetch_max(now, Ordering::Relaxed);
            LIVE.fetch_sub(l.size(), Ordering::Relaxed);
        }
        q
    }
}

#[global_allocator]
static A: Counting = Counting;

const CASES: &[(&str, &str, u32)] = &[
    ("plain cloth", "[effects]\ngravity = [0.0, -9.81, 0.0]\n", 120),
    (
        "wind, sphere, tethers",
        "[effects]\ngravity = [0.0, -9.81, 0.0]\n[effects.wind]\nvelocity = [3.0, 0.0, 1.0]\n\
         [[obstacle]]\nkind = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 0.5\n",
        120,
    ),
    (
        "self-collision",
        "[effects]\ngravity = [0.0, -9.81, 0.0]\n[effects.self_collision]\nresponse = \"vccpbd\"\n",
        120,
    ),
    (
        "implicit Euler",
        "[solver]\nmethod = \"implicit-euler\"\n[effects]\ngravity = [0.0, -9.81, 0.0]\n",
        80,
    ),
    (
        "implicit Euler, small",
        "[solver]\nmethod = \"implicit-euler\"\n[effects]\ngravity = [0.0, -9.81, 0.0]\n",
        40,
    ),
];

#[test]
fn estimate_is_within_a_factor_of_two_of_measured_peak() {
    let mut report = String::new();
    let mut worst: f64 = 1.0;
    for &(name, head, size) in CASES {
        let tethers = if name.contains("tethers") { "tethers = 0.05\n" } else { "" };
        let text = format!(
            "{head}[[cloth]]\nrows = {size}\ncols = {size}\nspacing = 0.01\norigin = [-0.8, 1.0, -0.8]\n\
             v = [0.0, 0.0, 1.0]\npins = [\"first-row-corners\"]\n{tethers}"
        );
        let scene = weft::scene::Scene::parse(&text, name).unwrap();
        let base = LIVE.load(Ordering::Relaxed);
        PEAK.store(base, Ordering::Relaxed);
        let mut w = scene.world().unwrap();
        let dt = w.params().dt;
        for _ in 0..3 {
            w.step(dt).unwrap();
        }
        let peak = (PEAK.load(Ordering::Relaxed) - base) as f64;
        let live = (LIVE.load(Ordering::Relaxed) - base) as f64;
        let estimate = w.memory_counts().bytes() as f64;
        assert!(
            scene.memory_counts().bytes() as f64 >= estimate,
            "{name}: scene counts below the world's"
        );
        let ratio = estimate / peak;
        report += &format!("{name}: estimate {estimate} B, measured peak {peak} B, live {live} B, estimate/peak {ratio:.2}\n");
        worst = worst.max(ratio).max(1.0 / ratio);
        drop(w);
    }
    eprint!("{report}");
    assert!(worst <= 2.0, "estimate off by more than a factor of two:\n{report}");
}
