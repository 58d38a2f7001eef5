//! The `weft` command end to end: run writes a summary and pictures that are not blank, check
//! reports bad scenes with their location, and resume equals an uninterrupted run.

mod common;

use common::{colour_fraction, glb, non_background_fraction};
use std::path::{Path, PathBuf};
use std::process::Command;

const SMALL: &str = r#"
[solver]
dt = 0.016666667
substeps = 4

[effects]
gravity = [0.0, -9.81, 0.0]

[[cloth]]
rows = 12
cols = 12
spacing = 0.05
origin = [-0.3, 1.0, 0.0]
v = [0.0, 0.0, 1.0]
fabric = "cotton"
pins = ["first-row-corners"]

[output]
steps = 30
frames = 3
width = 160
height = 120
"#;

fn weft() -> Command {
    Command::new(env!("CARGO_BIN_EXE_weft"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("weft-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write_scene(dir: &Path, text: &str) -> PathBuf {
    let p = dir.join("scene.toml");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn run_writes_summary_and_pictures() {
    let dir = tmp("run");
    let scene = write_scene(&dir, SMALL);
    let out = dir.join("out");
    let st = weft()
        .args(["run", "--quiet", "--obj", "--gif"])
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .status()
        .unwrap();
    assert!(st.success());
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["particles"], 144);
    assert_eq!(summary["steps"], 30);
    assert!(summary["ms_per_step_median"].as_f64().unwrap() > 0.0);
    assert!(summary["max_strain"].as_f64().unwrap() < 0.5);
    assert_eq!(summary["interrupted"], false);
    for f in ["final.png", "frames.png", "run.gif", "frame_000000.obj", "frame_000030.obj"] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    let frac = non_background_fraction(&out.join("final.png"));
    assert!(frac > 0.02 && frac < 0.9, "final.png foreground fraction {frac}");
    // No temporary files left behind.
    for e in std::fs::read_dir(&out).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().to_string();
        assert!(!name.ends_with(".tmp"), "left {name}");
    }
}

#[test]
fn check_reports_counts_and_bad_scenes() {
    let dir = tmp("check");
    let scene = write_scene(&dir, SMALL);
    let o = weft().arg("check").arg(&scene).output().unwrap();
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("particles     144"), "{text}");
    assert!(text.contains("effects on    gravity"), "{text}");
    assert!(text.contains("effects off   wind, drag"), "{text}");

    let bad = write_scene(&dir, &SMALL.replace("substeps = 4", "substeps = -4"));
    let o = weft().arg("check").arg(&bad).output().unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("line 4, column 12") && err.contains("-4"), "{err}");

    let o = weft().arg("check").arg(dir.join("missing.toml")).output().unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("missing.toml"));
}

#[test]
fn resumed_run_equals_uninterrupted_run() {
    let dir = tmp("resume");
    let scene = write_scene(&dir, SMALL);
    let full = dir.join("full");
    let part = dir.join("part");
    let ok = |c: &mut Command| assert!(c.status().unwrap().success());
    ok(weft()
        .args(["run", "--quiet", "--no-pictures", "--checkpoint-every", "30"])
        .arg(&scene)
        .arg("--out")
        .arg(&full));
    ok(weft()
        .args(["run", "--quiet", "--no-pictures", "--steps", "13", "--checkpoint-every", "13"])
        .arg(&scene)
        .arg("--out")
        .arg(&part));
    ok(weft()
        .args(["run", "--quiet", "--no-pictures", "--checkpoint-every", "30", "--resume"])
        .arg(part.join("checkpoint.bin"))
        .arg("--out")
        .arg(&part));
    let a = std::fs::read(full.join("checkpoint.bin")).unwrap();
    let b = std::fs::read(part.join("checkpoint.bin")).unwrap();
    assert_eq!(a, b, "resumed checkpoint differs from the uninterrupted one");
    let s: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(part.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["resumed_from_step"], 13);
    assert_eq!(s["steps"], 30);
}

#[cfg(unix)]
#[test]
fn ctrl_c_leaves_a_checkpoint_and_a_valid_summary() {
    let dir = tmp("sigint");
    let long = SMALL
        .replace("steps = 30", "steps = 10000000")
        .replace("rows = 12\ncols = 12", "rows = 60\ncols = 60");
    let scene = write_scene(&dir, &long);
    let out = dir.join("out");
    let mut child = weft()
        .args(["run", "--quiet", "--no-pictures", "--checkpoint-every", "50"])
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .spawn()
        .unwrap();
    // Wait until the run has written its first checkpoint, then interrupt it.
    let ck = out.join("checkpoint.bin");
    let t0 = std::time::Instant::now();
    while !ck.exists() && t0.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    assert!(ck.exists(), "no checkpoint after 60 s");
    let st = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(st.success());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "interrupted runs exit with 130");
    let s: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["interrupted"], true);
    let c = weft::world::checkpoint::Checkpoint::load(&ck).unwrap();
    assert_eq!(c.steps, s["steps"].as_u64().unwrap());
    assert!(c.steps > 0);
}

#[test]
fn check_lists_obstacles_and_refuses_unknown_keys() {
    let dir = tmp("obstacles");
    let text = format!(
        "{SMALL}\n[[obstacle]]\nkind = \"sphere\"\ncenter = [0.3, 0.0, 0.3]\nradius = 0.2\n\n[[obstacle]]\nkind = \"mesh\"\ndress_form = 400\nbroadphase = \"hash\"\nface_memory = true\n"
    );
    let scene = write_scene(&dir, &text);
    let o = weft().arg("check").arg(&scene).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("obstacles     2"), "{out}");
    assert!(
        out.contains("obstacle 0: sphere") && out.contains("obstacle 1: mesh of 400 faces, hash"),
        "{out}"
    );
    assert!(out.contains("face memory"), "{out}");
    let bad = write_scene(&dir, &text.replace("radius = 0.2", "radius = 0.2\nheight = 1.0"));
    let o = weft().arg("check").arg(&bad).output().unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("height"));
}

/// `--gltf` writes `run.glb`: it parses, holds the kept frames (the same steps `--obj` keeps)
/// as morph targets whose decoded positions are the OBJ files' vertices, and has normals.
#[test]
fn run_gltf_holds_the_kept_frames() {
    let dir = tmp("gltf");
    let out = dir.join("out");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/hanging.toml");
    let st = weft()
        .args([
            "run",
            "--quiet",
            "--no-pictures",
            "--gltf",
            "--obj",
            "--steps",
            "12",
            "--frames",
            "3",
        ])
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .status()
        .unwrap();
    assert!(st.success());
    let g = glb::parse(&std::fs::read(out.join("run.glb")).unwrap());
    let frames = g.frames("cloth_0");
    let steps = [0, 4, 8, 12];
    assert_eq!(frames.len(), steps.len());
    for (f, step) in steps.iter().enumerate() {
        let obj = std::fs::read_to_string(out.join(format!("frame_{step:06}.obj"))).unwrap();
        let verts: Vec<[f32; 3]> = obj
            .lines()
            .filter_map(|l| l.strip_prefix("v "))
            .map(|l| {
                let v: Vec<f32> = l.split(' ').map(|x| x.parse().unwrap()).collect();
                [v[0], v[1], v[2]]
            })
            .collect();
        assert_eq!(verts.len(), 1600);
        for (a, b) in frames[f].iter().zip(&verts) {
            assert!(
                (0..3).all(|k| (a[k] - b[k]).abs() <= 4.0 * f32::EPSILON),
                "frame {f}: {a:?} vs {b:?}"
            );
        }
    }
    assert_ne!(frames[0], frames[3], "the cloth moves");
    let normals = g.frames_of("cloth_0", "NORMAL");
    for n in normals.iter().flatten() {
        let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        assert!((l - 1.0).abs() < 1e-3, "normal {n:?}");
    }
    let input = g.json["animations"][0]["samplers"][0]["input"].as_u64().unwrap() as usize;
    let times = g.floats(input);
    let dt = 0.016666667f32;
    assert_eq!(times.len(), 4);
    assert!(times.iter().zip(steps).all(|(t, s)| (t - s as f32 * dt).abs() < 1e-4), "{times:?}");
}

/// A 0.3 m x 2 m strip dropped on a ground plane: the default camera frames the strip, not the
/// plane, so the (red) cloth covers a good part of the picture.
#[test]
fn the_default_camera_frames_the_cloth_not_the_plane() {
    let dir = tmp("framing");
    let scene = write_scene(
        &dir,
        r#"
[solver]
dt = 0.016666667
substeps = 4

[effects]
gravity = [0.0, -9.81, 0.0]

[[cloth]]
rows = 7
cols = 41
spacing = 0.05
origin = [-1.0, 0.2, -0.15]
u = [1.0, 0.0, 0.0]
v = [0.0, 0.0, 1.0]
fabric = "cotton"

[[obstacle]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]

[output]
steps = 30
frames = 2
width = 400
height = 300
"#,
    );
    let out = dir.join("out");
    let st = weft().args(["run", "--quiet"]).arg(&scene).arg("--out").arg(&out).status().unwrap();
    assert!(st.success());
    let red = colour_fraction(&out.join("final.png"), |r, g, b| {
        r as i32 > g as i32 + 40 && r as i32 > b as i32 + 40
    });
    // Framing the plane too left the strip at 0.8% of the picture; framed alone it covers 6.5%.
    assert!(red > 0.04, "the cloth covers only {:.1}% of the picture", red * 100.0);
}

/// A self-collision distance that would list every pair of two cloths stops the run at its
/// first step with the reason (exit code 2, as a diverged step).
#[test]
fn run_stops_when_self_collision_has_too_many_pairs() {
    let dir = tmp("pairs");
    let sheet = |y: f32| {
        format!("[[cloth]]\nrows = 40\ncols = 40\nspacing = 0.01\norigin = [0.0, {y}, 0.0]\nu = [1.0, 0.0, 0.0]\nv = [0.0, 0.0, 1.0]\n")
    };
    let text = format!(
        "[effects.self_collision]\ndistance = 1.0\n{}{}[output]\nsteps = 50\nframes = 1\n",
        sheet(1.0),
        sheet(1.02)
    );
    let scene = write_scene(&dir, &text);
    // `check` shows the reach the distance gives.
    let c = weft().arg("check").arg(&scene).output().unwrap();
    let shown = String::from_utf8_lossy(&c.stdout);
    assert!(
        shown.contains("self-collision distance 1 m") && shown.contains("travel 1 (reach 3 m)"),
        "{shown}"
    );
    let out = dir.join("out");
    let o = weft()
        .args(["run", "--quiet", "--no-pictures"])
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let warning = summary["warnings"][0].as_str().unwrap();
    assert!(
        warning.starts_with("step 1 ran without self-collision") && warning.contains("self_collision.distance"),
        "{warning}"
    );
    assert!(summary["self_collision"]["final_collision_pct"].is_null());
    assert_eq!(summary["self_collision"]["stats"]["failed_steps"], 1);
}
