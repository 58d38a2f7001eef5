//! Prints the NURBS global-vs-local timing table (SEEDS.md B) until the CLI's
//! `weft reproduce nurbs` exists: `cargo run --release --example nurbs_timing`.

use weft::strands::nurbs_timing::nurbs_timing;

fn main() {
    let ns = [8usize, 32, 128, 512, 2048, 4096];
    let rows = nurbs_timing(&ns, &[1, 3, 5], 256);
    println!(
        "{:<8} {:>6} {:>6} {:>14} {:>14} {:>8}",
        "kind", "n", "degree", "global ns/pt", "local ns/pt", "ratio"
    );
    for r in rows {
        println!(
            "{:<8} {:>6} {:>6} {:>14.1} {:>14.1} {:>8.1}",
            r.kind,
            r.n,
            r.degree,
            r.global_ns,
            r.local_ns,
            r.global_ns / r.local_ns
        );
    }
}
