//! Per-step self-collision phase times of the 100x100 `weft reproduce vccpbd` scene (basic
//! fabric, VcCPBD response, spatial hash, 10 substeps, one thread): shows which phase costs what
//! while the cloth falls (every step runs the broadphase) and after it has folded (lists reused).
//!
//! ```text
//! cargo run --release --example self_collision_timeline [steps] [threads] [response] [fabric] [tethers]
//! ```
//!
//! `response` is `vccpbd` (the default), `pbd` or `movement-speed`; `fabric` one of the presets
//! (`basic`, the default, `cotton`, `wool`, `polyester`); `tethers` a slack for tethers to the
//! pinned row (none by default, like the reproduction).
//!
//! Columns are ms for that step; `clamp` is the stage's total minus the listed phases (the speed
//! clamp with its mean velocity, summed in the predict pass, and bookkeeping); `rebuild` is 1
//! when the step ran the broadphase.

use weft::model::self_collision::{Response, SelfBroadphase, SelfCollision};
use weft::{Fabric, SolverParams};

fn main() -> weft::Result<()> {
    let mut args = std::env::args().skip(1).map(|a| a.parse::<usize>().ok());
    let steps = args.next().flatten().unwrap_or(150);
    let threads = args.next().flatten().unwrap_or(1);
    let response = match std::env::args().nth(3).as_deref() {
        None | Some("vccpbd") => Response::Vccpbd,
        Some("pbd") => Response::Pbd,
        Some("movement-speed") => Response::MovementSpeed,
        Some(other) => return Err(weft::WeftError::param("response", other, "must be vccpbd, pbd or movement-speed")),
    };
    let params = SolverParams {
        substeps: 10,
        iterations: 1,
        threads,
        ..Default::default()
    };
    let sc = SelfCollision {
        response,
        broadphase: SelfBroadphase::Hash,
        ..SelfCollision::default()
    };
    let fabric = Fabric::preset(&std::env::args().nth(4).unwrap_or_else(|| "basic".into()))?;
    let tethers = match std::env::args().nth(5) {
        None => None,
        Some(t) => Some(t.parse::<f32>().map_err(|e| weft::WeftError::param("tethers", t, e.to_string()))?),
    };
    let (mut w, dt) = weft::perf::fold_world_tethered(100, fabric, params, sc, tethers)?;
    println!("step   total   build   query   start   pairs    corr   clamp rebuild  pairs");
    let mut last = w.self_collision_stats().clone();
    for s in 0..steps {
        w.step(dt)?;
        let now = w.self_collision_stats().clone();
        let (p, q) = (&now.phases, &last.phases);
        let ms = |a: f64, b: f64| (a - b) * 1e3;
        let total = ms(now.time_s, last.time_s);
        let parts = [
            ms(p.build_s, q.build_s),
            ms(p.query_s, q.query_s),
            ms(p.step_start_s, q.step_start_s) - ms(p.build_s, q.build_s) - ms(p.query_s, q.query_s),
            ms(p.pairs_s, q.pairs_s),
            ms(p.correction_s, q.correction_s),
        ];
        let clamp = total - ms(p.step_start_s, q.step_start_s) - parts[3] - parts[4];
        print!("{s:4} {total:7.3}");
        for v in parts.iter().chain([&clamp]) {
            print!(" {v:7.3}");
        }
        println!(" {:7} {:6}", p.rebuilds - q.rebuilds, w.self_collision_pair_count());
        last = now;
    }
    Ok(())
}
