//! Golden runs: shipped scenes stepped a fixed number of times give the same bits as recorded.
//!
//! The hashes pin the step's arithmetic: a refactor that moves code must leave them unchanged;
//! a change that is meant to alter results updates them in the same commit and says why.
//! `GOLDEN_PRINT=1 cargo test --test golden -- --nocapture` prints the current hashes.

use std::path::Path;

use weft::scene::Scene;

/// FNV-1a over the bit patterns of every position and velocity.
fn state_hash(w: &weft::World) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for a in w.positions().iter().chain(w.velocities().iter()) {
        for f in a.iter() {
            for b in f.to_bits().to_le_bytes() {
                h ^= b as u64;
                h = h.wrapping_mul(0x0000_0100_0000_01b3);
            }
        }
    }
    h
}

/// Loads `scenes/NAME.toml`, applies `edit` to its `[solver]` section and steps it `steps` times.
fn run(name: &str, solver_extra: &str, self_extra: &str, steps: u32) -> u64 {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(format!("{name}.toml"));
    let text = std::fs::read_to_string(&path).unwrap();
    // Lines of the extras replace the scene's own lines for the same keys.
    let keys: Vec<&str> = solver_extra
        .lines()
        .chain(self_extra.lines())
        .filter_map(|l| l.split('=').next())
        .map(str::trim)
        .collect();
    let text: String = text
        .lines()
        .filter(|l| !keys.iter().any(|k| l.split('=').next().map(str::trim) == Some(*k)))
        .map(|l| format!("{l}\n"))
        .collect();
    let text = text.replacen("[solver]", &format!("[solver]\n{solver_extra}"), 1);
    let text = text.replacen("[effects.self_collision]", &format!("[effects.self_collision]\n{self_extra}"), 1);
    let scene = Scene::parse(&text, name).unwrap();
    let dt = scene.solver.params().dt;
    let mut w = scene.world().unwrap();
    for _ in 0..steps {
        w.step(dt).unwrap_or_else(|e| panic!("{name} [{solver_extra}]: {e}"));
    }
    state_hash(&w)
}

fn check(cases: &[(&str, &str, &str, u32, u64)]) {
    let print = std::env::var_os("GOLDEN_PRINT").is_some();
    let mut wrong = Vec::new();
    for &(name, solver, selfc, steps, want) in cases {
        let got = run(name, solver, selfc, steps);
        if print {
            println!("(\"{name}\", {solver:?}, {selfc:?}, {steps}, 0x{got:016x}),");
        }
        if got != want {
            wrong.push(format!("{name} [{solver}] [{selfc}]: 0x{got:016x}, recorded 0x{want:016x}"));
        }
    }
    assert!(
        wrong.is_empty(),
        "state hashes differ from the recorded ones:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn shipped_scenes_give_the_recorded_bits() {
    check(&[
        ("hanging", "", "", 30, 0x0f89c93b8456551d),
        ("hanging", "backend = \"scalar\"", "", 10, 0x5fd30b92af850b80),
        ("drape-sphere", "", "", 30, 0xc0deff2c44bacc6b),
        ("drape-form", "", "", 20, 0x64eae10c13d10171),
        ("fold", "", "", 90, 0x24294581eec818cd),
        ("fold", "", "response = \"pbd\"\nbroadphase = \"aabb-tree\"", 90, 0x4770e104dfec94b8),
        ("fold", "", "response = \"movement-speed\"", 90, 0x8d9ae4f71823e983),
        ("fold", "backend = \"scalar\"", "", 60, 0x138262cdeac383ef),
        ("hair", "", "", 10, 0xe0b04c2cf736067f),
        ("flag", "", "", 20, 0x37a43e74da47d078),
    ]);
}

#[test]
fn force_based_methods_give_the_recorded_bits() {
    check(&[
        (
            "hanging-soft",
            "method = \"symplectic-euler\"\nsubsteps = 400",
            "",
            5,
            0x2ecf12f154785637,
        ),
        ("hanging-soft", "method = \"leapfrog\"\nsubsteps = 400", "", 5, 0x5936a84aa28070e2),
        ("hanging-soft", "method = \"implicit-euler\"", "", 5, 0xa94d86a1eee772b5),
        (
            "drape-sphere",
            "method = \"implicit-euler\"\nsubsteps = 2",
            "",
            3,
            0x290568735d4a9885,
        ),
        ("fold", "method = \"implicit-euler\"\nsubsteps = 2", "", 3, 0xaf71cf2d13c216c1),
    ]);
}
