//! Replays the saved fuzz corpus (fuzz/corpus/<target>/*) through the same entry points the
//! fuzzers run, so CI covers every input that ever found a bug or new coverage.

use std::path::Path;

fn replay(target: &str, f: fn(&[u8])) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus").join(target);
    let mut count = 0;
    let mut entries: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    for p in entries {
        let data = std::fs::read(&p).unwrap();
        if std::panic::catch_unwind(|| f(&data)).is_err() {
            panic!("{} panicked (above)", p.display());
        }
        count += 1;
    }
    assert!(count > 0, "no corpus in {}", dir.display());
}

#[test]
fn scene_corpus() {
    replay("scene", weft::fuzzing::scene_bytes);
}

#[test]
fn step_corpus() {
    replay("step", weft::fuzzing::step_bytes);
}

#[test]
fn obj_corpus() {
    replay("obj", weft::fuzzing::obj_bytes);
}

#[test]
fn checkpoint_corpus() {
    replay("checkpoint", weft::fuzzing::checkpoint_bytes);
    // The checkpoints written by `weft run` decode and resume; the damaged ones are refused.
    use weft::world::checkpoint::Checkpoint;
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus/checkpoint");
    for good in ["method_xpbd", "self_hash_vccpbd", "strands_ellipsoid_cloth", "obstacle_mesh_grid"] {
        let c = Checkpoint::load(&dir.join(format!("{good}.bin"))).unwrap();
        let mut w = weft::scene::Scene::parse(&c.scene, good).unwrap().world().unwrap();
        w.restore(&c).unwrap();
    }
    for bad in ["flipped", "truncated", "unhashed_body", "unhashed_huge_count"] {
        assert!(Checkpoint::load(&dir.join(format!("{bad}.bin"))).is_err(), "{bad}");
    }
}

/// The scene seeds reach every stage: each `obstacle_*`, `self_*`, `method_*` and `strands_*`
/// seed builds a world, and together they name every obstacle kind and mesh broadphase, both
/// self-collision broadphases with every response, every method and strands on both scalps.
#[test]
fn scene_seeds_reach_every_stage() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus/scene");
    let mut seen = std::collections::BTreeSet::new();
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_stem().unwrap().to_string_lossy().to_string();
        if !["obstacle_", "self_", "method_", "strands_"].iter().any(|k| name.starts_with(k)) {
            continue;
        }
        let text = std::fs::read_to_string(&p).unwrap();
        let scene = weft::scene::Scene::parse(&text, &name).unwrap_or_else(|e| panic!("{name}: {e}"));
        let w = scene.world().unwrap();
        for o in w.obstacles() {
            seen.insert(o.describe().split_whitespace().next().unwrap_or("").to_string());
        }
        if let Some(c) = w.self_collision() {
            seen.insert(format!("self {} {}", c.broadphase.name(), c.response.name()));
        }
        seen.insert(format!("method {}", w.params().method.name()));
        for g in w.strands() {
            seen.insert(format!("strands {}", if g.scalp.is_sphere() { "sphere" } else { "ellipsoid" }));
        }
        for line in text
            .lines()
            .filter(|l| l.starts_with("broadphase") && text.contains("kind = \"mesh\""))
        {
            seen.insert(format!("mesh {}", line.split('"').nth(1).unwrap_or("")));
        }
    }
    let mut want: Vec<String> = ["mesh grid", "mesh bvh", "mesh hash", "strands sphere", "strands ellipsoid"]
        .map(String::from)
        .to_vec();
    for m in weft::Method::ALL {
        want.push(format!("method {}", m.name()));
    }
    for bp in ["hash", "aabb-tree"] {
        for r in ["vccpbd", "pbd", "movement-speed"] {
            want.push(format!("self {bp} {r}"));
        }
    }
    for w in &want {
        assert!(seen.contains(w), "no seed reaches `{w}`; seen {seen:?}");
    }
    // Obstacle kinds: the first word of each description.
    let kinds: Vec<_> = seen.iter().filter(|s| !s.contains(' ')).collect();
    assert!(kinds.len() >= 5, "obstacle kinds seen: {kinds:?}");
}
