//! `weft reproduce nurbs [--json]`: the thesis' complexity claim for NURBS evaluation (the thesis on
//! NURBS strands and surfaces, section 2.2.2): a point costs `O(n)` with the global sum and `O(k)` with the local one, so
//! local time per point must stay flat as the number of control points `n` grows while global
//! time grows with `n` (with `n²` for an `n x n` surface). Measured by
//! [`weft::strands::nurbs_timing::nurbs_timing`]; surfaces stop at
//! [`SURFACE_MAX_N`](weft::strands::nurbs_timing::SURFACE_MAX_N) per direction.

use std::process::ExitCode;

use clap::Args;
use serde::Serialize;
use weft::strands::nurbs_timing::{nurbs_timing, NurbsTimingRow, SURFACE_MAX_N};
use weft::WeftError;

/// Control-point counts timed: 8, 16, ..., 4096.
pub const NS: [usize; 10] = [8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096];

/// Degrees timed (the paper's order k = degree + 1).
pub const DEGREES: [usize; 3] = [2, 3, 4];

#[derive(Args)]
pub struct NurbsArgs {
    /// Print one JSON array of {kind, n, degree, global_ns, local_ns} instead of the table.
    #[arg(long)]
    json: bool,
    /// Parameters evaluated per measurement (each measurement is the median of several runs).
    #[arg(long, default_value_t = 256)]
    samples: usize,
    /// Largest n timed (for a quick look; the full table goes to 4096).
    #[arg(long, default_value_t = 4096)]
    max_n: usize,
}

#[derive(Serialize)]
struct JsonRow {
    kind: &'static str,
    n: usize,
    degree: usize,
    global_ns: f64,
    local_ns: f64,
}

/// Ratio of the last to the first entry of `f` over rows of one kind and degree.
fn growth(rows: &[&NurbsTimingRow], f: impl Fn(&NurbsTimingRow) -> f64) -> f64 {
    match (rows.first(), rows.last()) {
        (Some(a), Some(b)) => f(b) / f(a),
        _ => f64::NAN,
    }
}

/// The table and, per kind and degree, how much each cost grew from the smallest to the largest
/// n.
pub fn text(rows: &[NurbsTimingRow]) -> String {
    let mut s = format!(
        "NURBS evaluation, ns per point (median), global vs local (the NURBS thesis chapter on thin objects)\n{:<8} {:>6} {:>6} {:>14} {:>12} {:>10}\n",
        "kind", "n", "degree", "global ns/pt", "local ns/pt", "global/loc"
    );
    for r in rows {
        s += &format!(
            "{:<8} {:>6} {:>6} {:>14.1} {:>12.1} {:>10.1}\n",
            r.kind,
            r.n,
            r.degree,
            r.global_ns,
            r.local_ns,
            r.global_ns / r.local_ns
        );
    }
    s += "\ngrowth from the smallest to the largest n (local should stay near 1x):\n";
    for kind in ["curve", "surface"] {
        for &p in &DEGREES {
            let sel: Vec<&NurbsTimingRow> = rows.iter().filter(|r| r.kind == kind && r.degree == p).collect();
            if sel.len() < 2 {
                continue;
            }
            let (n0, n1) = (sel[0].n, sel[sel.len() - 1].n);
            s += &format!(
                "  {kind:<7} degree {p}: n {n0} -> {n1}: global x{:.1}, local x{:.2}\n",
                growth(&sel, |r| r.global_ns),
                growth(&sel, |r| r.local_ns)
            );
        }
    }
    s += &format!("(surfaces are n x n grids, timed up to n = {SURFACE_MAX_N})\n");
    s
}

pub fn run(args: NurbsArgs) -> weft::Result<ExitCode> {
    if args.samples == 0 {
        return Err(WeftError::param("--samples", 0, "at least one sample is needed"));
    }
    let ns: Vec<usize> = NS.iter().copied().filter(|&n| n <= args.max_n).collect();
    if ns.is_empty() {
        return Err(WeftError::param("--max-n", args.max_n, format!("must be at least {}", NS[0])));
    }
    let rows = nurbs_timing(&ns, &DEGREES, args.samples);
    if args.json {
        let json: Vec<JsonRow> = rows
            .iter()
            .map(|r| JsonRow {
                kind: r.kind,
                n: r.n,
                degree: r.degree,
                global_ns: r.global_ns,
                local_ns: r.local_ns,
            })
            .collect();
        let out = serde_json::to_string_pretty(&json).map_err(|e| WeftError::Scene(format!("cannot write JSON: {e}")))?;
        println!("{out}");
    } else {
        print!("{}", text(&rows));
    }
    Ok(ExitCode::SUCCESS)
}
