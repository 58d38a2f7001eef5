//! End-to-end: `weft accuracy --json` and `weft reproduce small-steps --json`.

use std::process::Command;

const SCENE: &str = r#"
[solver]
dt = 0.02
[effects]
gravity = [0.0, -9.81, 0.0]
[[cloth]]
rows = 4
cols = 4
spacing = 0.05
v = [0.0, 0.0, 1.0]
fabric = "cotton"
pins = ["first-row-corners"]
"#;

#[test]
fn accuracy_json_has_every_field_and_no_nan_and_the_cache_is_reused() {
    let dir = std::env::temp_dir().join(format!("weft-accuracy-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("tiny.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let svg = dir.join("plot.svg");
    let run = || {
        Command::new(env!("CARGO_BIN_EXE_weft"))
            .args([
                "accuracy",
                scene.to_str().unwrap(),
                "--json",
                "--time",
                "0.1",
                "--reference-substeps",
                "64",
            ])
            .args(["--out", dir.to_str().unwrap(), "--plot", svg.to_str().unwrap()])
            .output()
            .unwrap()
    };
    let out = run();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(!text.contains("NaN") && !text.contains("inf"));
    let rows: Vec<serde_json::Value> = serde_json::from_str(&text).unwrap();
    assert_eq!(rows.len(), 25);
    for r in &rows {
        for key in [
            "method",
            "substeps",
            "iterations",
            "precision",
            "ms_per_step",
            "rms_error",
            "max_error",
            "energy_drift",
            "max_penetration",
            "pareto",
        ] {
            assert!(r.get(key).is_some(), "{key} missing in {r}");
        }
        let diverged = r["status"] == "diverged";
        assert_eq!(r["rms_error"].is_null(), diverged, "{r}");
    }
    // Stiff cotton at 64 explicit substeps of 0.02 s diverges; the table says so.
    assert!(rows.iter().any(|r| r["method"] == "symplectic-euler" && r["status"] == "diverged"));
    assert!(rows.iter().any(|r| r["pareto"] == true));
    let plot = std::fs::read_to_string(&svg).unwrap();
    assert!(plot.starts_with("<svg"));
    // Every plotted point carries its label: substeps x iterations (method by colour).
    for r in rows.iter().filter(|r| !r["rms_error"].is_null()) {
        let label = format!(">\n{}x{}\n</text>", r["substeps"], r["iterations"]);
        let want = rows
            .iter()
            .filter(|q| !q["rms_error"].is_null() && q["substeps"] == r["substeps"] && q["iterations"] == r["iterations"])
            .count();
        assert_eq!(plot.matches(&label).count(), want, "label {label}");
    }
    let refs = || {
        std::fs::read_dir(&dir)
            .unwrap()
            .filter(|e| e.as_ref().unwrap().file_name().to_string_lossy().starts_with("reference-"))
            .count()
    };
    assert_eq!(refs(), 1);
    assert!(run().status.success());
    assert_eq!(refs(), 1, "second run reuses the cached reference");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn reproduce_small_steps_json_prints_ours_beside_theirs() {
    let out = Command::new(env!("CARGO_BIN_EXE_weft"))
        .args(["reproduce", "small-steps", "--json"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let rows: Vec<serde_json::Value> = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(rows.len(), 4);
    assert_eq!(rows[0]["paper"], 322.0);
    assert_eq!(rows[3]["paper"], 3.2);
    let f64_iter = rows[1]["constraint_error"].as_f64().unwrap();
    let f64_sub = rows[3]["constraint_error"].as_f64().unwrap();
    assert!(f64_iter > 5.0 * f64_sub, "{f64_iter} vs {f64_sub}");
}

#[test]
fn accuracy_writes_a_png_plot_that_decodes() {
    let dir = std::env::temp_dir().join(format!("weft-accuracy-png-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("tiny.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let png_path = dir.join("plot.png");
    let out = Command::new(env!("CARGO_BIN_EXE_weft"))
        .args([
            "accuracy",
            scene.to_str().unwrap(),
            "--json",
            "--time",
            "0.04",
            "--reference-substeps",
            "16",
        ])
        .args(["--out", dir.to_str().unwrap(), "--plot", png_path.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png_path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (900, 600));
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let px = &buf[..info.buffer_size()];
    let white = px.chunks(3).filter(|p| p == &[255, 255, 255]).count();
    let dark = px.chunks(3).filter(|p| p.iter().all(|&c| c < 64)).count();
    let blue = px.chunks(3).filter(|p| p == &[0, 0, 255]).count();
    assert!(white > px.len() / 6, "mostly white background");
    assert!(dark > 500, "axes and text drawn: {dark} dark pixels");
    assert!(blue > 50, "xpbd points drawn: {blue} blue pixels");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn accuracy_refuses_other_plot_formats_and_bad_time() {
    let out = Command::new(env!("CARGO_BIN_EXE_weft"))
        .args(["accuracy", "scenes/hanging.toml", "--plot", "x.jpg"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains(".png"));
    let out = Command::new(env!("CARGO_BIN_EXE_weft"))
        .args(["accuracy", "scenes/hanging.toml", "--time", "0"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--time"));
}
