//! The `weft` command with hair: a strand scene runs and draws its strands, `check` lists the
//! strands, cloth can be drawn as a NURBS surface, and `reproduce nurbs` prints its table.

mod common;

use common::non_background_fraction;
use std::path::PathBuf;
use std::process::Command;

const HAIR: &str = r#"
[solver]
substeps = 6

[effects]
gravity = [0.0, -9.81, 0.0]
[effects.wind]
velocity = [3.0, 0.0, 0.0]

[[strands]]
count = 300
points = 8
segment_length = 0.015
bend_compliance = 1.0
mass = 0.000002
thickness = 0.0005
scalp = { kind = "ellipsoid", center = [0.0, 1.6, 0.0], radii = [0.09, 0.1, 0.1], polar_degrees = [0.0, 100.0] }

[[cloth]]
rows = 10
cols = 10
spacing = 0.04
origin = [0.3, 1.8, 0.0]
pins = ["first-row-corners"]

[output]
steps = 10
frames = 2
width = 160
height = 120
"#;

fn weft() -> Command {
    Command::new(env!("CARGO_BIN_EXE_weft"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("weft-cli-strands-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn hair_scene_runs_and_draws_strands_and_a_nurbs_cloth() {
    let dir = tmp("run");
    let scene = dir.join("hair.toml");
    std::fs::write(&scene, HAIR).unwrap();
    for (sub, extra) in [("plain", None), ("nurbs", Some("--nurbs-surface"))] {
        let out = dir.join(sub);
        let mut cmd = weft();
        cmd.arg("run").arg(&scene).arg("--out").arg(&out).arg("-q");
        if let Some(e) = extra {
            cmd.arg(e);
        }
        let o = cmd.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let f = non_background_fraction(&out.join("final.png"));
        assert!(f > 0.02, "{sub}: picture nearly blank ({f})");
        let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
        assert_eq!(summary["particles"], 300 * 8 + 100);
    }
}

#[test]
fn check_lists_strands() {
    let dir = tmp("check");
    let scene = dir.join("hair.toml");
    std::fs::write(&scene, HAIR).unwrap();
    let o = weft().arg("check").arg(&scene).output().unwrap();
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("strands       300"), "{text}");
    assert!(text.contains("300 x 8 points on a ellipsoid"), "{text}");
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, HAIR.replace("count = 300", "count = -3")).unwrap();
    let o = weft().arg("check").arg(&bad).output().unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("line 11, column 9"), "{err}");
}

#[test]
fn reproduce_nurbs_prints_json_and_a_table() {
    let o = weft()
        .args(["reproduce", "nurbs", "--json", "--samples", "4", "--max-n", "32"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows: Vec<serde_json::Value> = serde_json::from_slice(&o.stdout).unwrap();
    // n = 8, 16, 32 x degree 2, 3, 4, for curves and surfaces.
    assert_eq!(rows.len(), 18);
    for r in &rows {
        let keys: Vec<&str> = r.as_object().unwrap().keys().map(|k| k.as_str()).collect();
        assert_eq!(keys.len(), 5, "{r}");
        for k in ["kind", "n", "degree", "global_ns", "local_ns"] {
            assert!(r.get(k).is_some(), "{k} missing in {r}");
        }
        assert!(r["global_ns"].as_f64().unwrap() > 0.0 && r["local_ns"].as_f64().unwrap() > 0.0);
        assert!((2..=4).contains(&r["degree"].as_u64().unwrap()));
    }
    assert_eq!(rows.iter().filter(|r| r["kind"] == "surface").count(), 9);
    let o = weft()
        .args(["reproduce", "nurbs", "--samples", "4", "--max-n", "16"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("global ns/pt") && text.contains("curve   degree 3: n 8 -> 16"),
        "{text}"
    );
    let o = weft().args(["reproduce", "nurbs", "--max-n", "4"]).output().unwrap();
    assert!(!o.status.success(), "--max-n below 8 is an error");
}
