//! `weft reproduce vccpbd --json` prints the paper's 48 rows with our figures, and `weft run`
//! reports the average collision in summary.json when self-collision is on.

use std::process::Command;

fn weft() -> Command {
    Command::new(env!("CARGO_BIN_EXE_weft"))
}

#[test]
fn reproduce_vccpbd_json_has_every_row() {
    let out = weft().args(["reproduce", "vccpbd", "--steps", "2", "--json"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let rows: Vec<serde_json::Value> = serde_json::from_slice(&out.stdout).unwrap();
    // 3 sizes x 4 fabrics x (3 responses with the hash + VcCPBD with the AABB tree).
    assert_eq!(rows.len(), 48);
    for r in &rows {
        for key in ["collision_ms", "step_ms", "avg_collision_pct", "paper_ms"] {
            let v = r[key].as_f64().unwrap_or(f64::NAN);
            assert!(v.is_finite() && v >= 0.0, "{key} in {r}");
        }
        assert!(r["step_ms"].as_f64() >= r["collision_ms"].as_f64(), "{r}");
    }
    let pick = |particles: u64, fabric: &str, response: &str, bp: &str| {
        rows.iter()
            .find(|r| r["particles"] == particles && r["fabric"] == fabric && r["response"] == response && r["broadphase"] == bp)
            .unwrap_or_else(|| panic!("row {particles} {fabric} {response} {bp}"))
    };
    assert_eq!(pick(1156, "basic", "movement-speed", "hash")["paper_ms"], 2.290);
    assert_eq!(pick(10000, "wool", "pbd", "hash")["paper_ms"], 30.080);
    assert_eq!(pick(2500, "polyester", "vccpbd", "aabb-tree")["paper_ms"], 5.396);
}

#[test]
fn run_summary_reports_average_collision() {
    let dir = std::env::temp_dir().join(format!("weft-selfcol-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("fold.toml");
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/fold.toml"))
        .unwrap()
        .replace("steps = 240", "steps = 12");
    std::fs::write(&scene, text).unwrap();
    let out = weft()
        .args([
            "run",
            scene.to_str().unwrap(),
            "--no-pictures",
            "-q",
            "--out",
            dir.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let s: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("summary.json")).unwrap()).unwrap();
    let sc = &s["self_collision"];
    assert_eq!(sc["response"], "vccpbd");
    assert_eq!(sc["stats"]["measured"], 12);
    assert!(sc["avg_collision_pct"].as_f64().unwrap() >= 0.0);
    assert!(sc["collision_ms_per_step"].as_f64().unwrap() > 0.0);
    let _ = std::fs::remove_dir_all(&dir);
}
