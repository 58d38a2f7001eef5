//! `weft bench --self-collision --json`: one JSON object a scene and thread count, with the
//! field names the suite's issue fixes, and figures that can be checked without timing.

use std::process::Command;

#[test]
fn bench_self_collision_json_has_the_fields_and_plausible_figures() {
    let out = Command::new(env!("CARGO_BIN_EXE_weft"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["bench", "--self-collision", "--json", "--only", "flag,twist", "--steps", "4"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    let rows: Vec<serde_json::Value> = text.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(rows.len(), 4, "two scenes on 1 and 2 threads: {text}");
    for r in &rows {
        for key in [
            "scene",
            "particles",
            "substeps",
            "threads",
            "collision_ns_per_particle_substep",
            "step_ms_median",
            "step_ms_p95",
            "step_ms_median_without",
            "avg_collision_pct",
            "max_violation_m",
        ] {
            assert!(r.get(key).is_some(), "{key} missing in {r}");
        }
        assert_eq!(r["substeps"], 10);
        assert!(r["collision_ns_per_particle_substep"].as_f64().unwrap() > 0.0);
        assert!(r["step_ms_p95"].as_f64().unwrap() >= r["step_ms_median"].as_f64().unwrap());
        // the 1-thread run's median over this run's: 1 on one thread, positive on two
        let speedup = r["speedup_over_1_thread"].as_f64().unwrap();
        if r["threads"] == 1 {
            assert_eq!(speedup, 1.0);
        } else {
            assert!(speedup > 0.0 && speedup.is_finite());
        }
    }
    for pair in rows.chunks(2) {
        let (one, two) = (&pair[0], &pair[1]);
        let ratio = one["step_ms_median"].as_f64().unwrap() / two["step_ms_median"].as_f64().unwrap();
        let speedup = two["speedup_over_1_thread"].as_f64().unwrap();
        assert!((speedup - ratio).abs() <= 1e-12 * ratio, "{speedup} against {ratio}");
    }
    assert_eq!(rows[0]["scene"], "twist");
    assert_eq!(rows[0]["particles"], 4000);
    assert_eq!(rows[2]["scene"], "flag");
    assert_eq!(rows[2]["particles"], 2400);
    assert_eq!(rows[3]["threads"], 2);
    // A scene name that is not in the suite is refused.
    let bad = Command::new(env!("CARGO_BIN_EXE_weft"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["bench", "--self-collision", "--only", "nope", "--steps", "1"])
        .output()
        .unwrap();
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("nope"));
    assert!(rows.iter().all(|r| r["travel"] == 1.0), "the scenes' own travel");
}

/// `--travel` replaces every scene's travel bound; the library refuses one out of range.
#[test]
fn bench_self_collision_travel() {
    let run = |travel: &str| {
        Command::new(env!("CARGO_BIN_EXE_weft"))
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .args([
                "bench",
                "--self-collision",
                "--json",
                "--only",
                "flag",
                "--steps",
                "2",
                "--travel",
                travel,
            ])
            .output()
            .unwrap()
    };
    let out = run("0.5");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    let rows: Vec<serde_json::Value> = text.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    assert_eq!(rows.len(), 2);
    assert!(rows.iter().all(|r| r["travel"] == 0.5), "{text}");
    let bad = run("3");
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("self_collision.travel"));
}
