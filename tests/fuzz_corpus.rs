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
        f(&data);
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
