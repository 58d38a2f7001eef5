//! Times the self-collision hash queries on snapshots of the 100x100 `weft reproduce vccpbd`
//! fold (basic fabric, VcCPBD): a falling step (reach 3 d) and a folded one (reach
//! 5 d, the skin's rebuild), the particle query and the cell query on the same build, many
//! repetitions on a pool of `threads` (1 unless given), min and median (the min is robust to
//! a loaded machine).
//!
//! ```text
//! cargo run --release --example self_query_bench [fall_step] [folded_step] [reps] [cell %] [threads]
//! ```

use std::time::Instant;
use weft::model::self_collision::{Response, SelfBroadphase, SelfCollision};
use weft::self_collision::hash::SpatialHash;
use weft::self_collision::neighbours::Neighbours;
use weft::{Fabric, SolverParams};

fn main() -> weft::Result<()> {
    let mut args = std::env::args().skip(1).map(|a| a.parse::<usize>().ok());
    let at: Vec<usize> = vec![args.next().flatten().unwrap_or(20), args.next().flatten().unwrap_or(46)];
    let reps = args.next().flatten().unwrap_or(200);
    // Hash cell side over the reach, in percent (100: the stage's `CELL_FACTOR`).
    let cell = args.next().flatten().unwrap_or(100) as f32 / 100.0;
    // Threads of the queries (the world itself steps on one).
    let query_threads = args.next().flatten().unwrap_or(1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(query_threads)
        .build()
        .map_err(|e| weft::WeftError::param("threads", query_threads, e.to_string()))?;
    let threads = 1;
    let params = SolverParams {
        substeps: 10,
        iterations: 1,
        threads,
        ..Default::default()
    };
    let sc = SelfCollision {
        response: Response::Vccpbd,
        broadphase: SelfBroadphase::Hash,
        ..SelfCollision::default()
    };
    let (mut w, dt) = weft::perf::fold_world(100, Fabric::preset("basic")?, params, sc)?;
    let (size, spacing) = (100u32, 1.0 / 99.0f32);
    let n = w.particle_count();
    // Rest positions of the grid (the cloth's own: row-major, spacing apart) and one cloth.
    let rest: [Vec<f32>; 3] = [
        (0..n).map(|i| (i % size as usize) as f32 * spacing).collect(),
        (0..n).map(|i| (i / size as usize) as f32 * spacing).collect(),
        vec![0.0; n],
    ];
    let cloth = vec![0u32; n];
    let d = spacing;
    let mut done = 0;
    for &(stop, reach) in &[(at[0], 3.0 * d), (at[1], 5.0 * d)] {
        while done < stop {
            w.step(dt)?;
            done += 1;
        }
        let x = w.positions();
        let mut h = SpatialHash::new(n);
        let mut out = Neighbours::new();
        let (mut tb, mut tp, mut tc) = (Vec::new(), Vec::new(), Vec::new());
        pool.install(|| -> weft::Result<()> {
            for _ in 0..reps {
                let t0 = Instant::now();
                h.build(x[0], x[1], x[2], n, reach * cell)?;
                h.attach_rest([&rest[0], &rest[1], &rest[2]], &cloth)?;
                tb.push(t0.elapsed().as_secs_f64() * 1e3);
                let t0 = Instant::now();
                h.query_upper_unskipped(reach, 3.003 * d, &mut out)?;
                tp.push(t0.elapsed().as_secs_f64() * 1e3);
                let t0 = Instant::now();
                h.query_upper_unskipped_cells(reach, 3.003 * d, &mut out)?;
                tc.push(t0.elapsed().as_secs_f64() * 1e3);
            }
            Ok(())
        })?;
        let st = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            format!("min {:.3} median {:.3}", v[0], v[v.len() / 2])
        };
        let cs = h.cell_start();
        let occupied = cs.windows(2).filter(|w| w[1] > w[0]).count();
        println!(
            "step {stop} reach {:.0} d, {:.1} particles a bucket, {} pairs: build+attach {} | particle query {} | cell query {} (ms)",
            reach / d,
            n as f64 / occupied.max(1) as f64,
            out.total(),
            st(&mut tb),
            st(&mut tp),
            st(&mut tc)
        );
    }
    Ok(())
}
