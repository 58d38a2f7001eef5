//! Inputs that once took the machine down, run through the `weft` binary: each must exit
//! non-zero at once with a message, without reading or allocating in proportion to the input.
//! (`/usr/bin/time -v` on the same commands shows the maximum resident size; the tests check
//! the exit code, the message and that the command returns.)

use std::path::PathBuf;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn weft(args: &[&str], env: Option<(&str, &str)>) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_weft"));
    c.args(args);
    if let Some((k, v)) = env {
        c.env(k, v);
    }
    let t0 = Instant::now();
    let out = c.output().unwrap();
    // Generous against a loaded machine; the failure mode guarded against ran for minutes.
    assert!(t0.elapsed() < Duration::from_secs(30), "weft {args:?} took {:?}", t0.elapsed());
    out
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("weft-bad-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn refused(out: &Output, needle: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "exit {:?}; stderr {err}", out.status);
    assert!(err.contains(needle), "stderr does not mention `{needle}`: {err}");
}

#[cfg(unix)]
#[test]
fn device_files_are_refused_everywhere() {
    refused(&weft(&["check", "/dev/zero"], None), "not a regular file");
    refused(&weft(&["run", "--resume", "/dev/zero"], None), "not a regular file");
    let d = tmp("devobj");
    let scene = d.join("s.toml");
    std::fs::write(
        &scene,
        "[[cloth]]\nrows = 4\ncols = 4\nspacing = 0.1\n[[obstacle]]\nkind = \"mesh\"\nobj = \"/dev/zero\"\n",
    )
    .unwrap();
    refused(&weft(&["check", scene.to_str().unwrap()], None), "not a regular file");
    refused(&weft(&["check", d.to_str().unwrap()], None), "not a regular file");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn oversized_files_are_refused_by_size() {
    let d = tmp("big");
    let scene = d.join("big.toml");
    // One byte over the scene limit, a comment, so only the size can refuse it.
    let f = std::fs::File::create(&scene).unwrap();
    f.set_len(weft::files::SCENE_LIMIT + 1).unwrap();
    refused(&weft(&["check", scene.to_str().unwrap()], None), "more than the limit");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn a_cloth_beyond_the_memory_limit_is_refused_before_it_is_built() {
    let d = tmp("huge");
    let scene = d.join("huge.toml");
    std::fs::write(&scene, "[[cloth]]\nrows = 15000\ncols = 15000\nspacing = 0.01\n").unwrap();
    // 225 M particles: about 120 GiB by the estimate, more than this machine (and CI) has
    // available; WEFT_MEMORY_LIMIT makes the outcome independent of the machine.
    let s = scene.to_str().unwrap();
    for cmd in [vec!["check", s], vec!["run", s, "--out", d.to_str().unwrap()]] {
        let out = weft(&cmd, Some(("WEFT_MEMORY_LIMIT", "8G")));
        refused(&out, "estimated");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("8.0 GiB") && err.contains("WEFT_MEMORY_LIMIT"), "{err}");
    }
    // Without the variable, MemAvailable (where it exists) refuses it too.
    if std::path::Path::new("/proc/meminfo").exists() {
        refused(&weft(&["check", s], None), "MemAvailable");
    }
    // A small scene under a small limit: the limit applies to what fits elsewhere as well.
    std::fs::write(&scene, "[[cloth]]\nrows = 100\ncols = 100\nspacing = 0.01\n").unwrap();
    refused(&weft(&["check", s], Some(("WEFT_MEMORY_LIMIT", "1M"))), "WEFT_MEMORY_LIMIT");
    let ok = weft(&["check", s], Some(("WEFT_MEMORY_LIMIT", "1G")));
    assert!(ok.status.success(), "{}", String::from_utf8_lossy(&ok.stderr));
    refused(&weft(&["check", s], Some(("WEFT_MEMORY_LIMIT", "lots"))), "WEFT_MEMORY_LIMIT");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn checkpoint_length_fields_are_checked_before_allocating() {
    use weft::world::checkpoint::Checkpoint;
    // A checkpoint whose particle count and scene length claim 2^60 entries, hashed correctly
    // so that only the length checks can refuse it.
    let mut b = b"WEFTCKP1".to_vec();
    b.extend_from_slice(&1u32.to_le_bytes());
    b.extend_from_slice(&0u64.to_le_bytes());
    b.extend_from_slice(&0f64.to_le_bytes());
    for (n, scene_len) in [(1u64 << 60, 0u64), (0, 1 << 60), (u64::MAX, u64::MAX)] {
        let mut c = b.clone();
        c.extend_from_slice(&n.to_le_bytes());
        c.extend_from_slice(&scene_len.to_le_bytes());
        let mut h = 0xcbf29ce484222325u64;
        for &x in &c {
            h ^= x as u64;
            h = h.wrapping_mul(0x100000001b3);
        }
        c.extend_from_slice(&h.to_le_bytes());
        let e = Checkpoint::from_bytes(&c).unwrap_err().to_string();
        assert!(e.contains("truncated") || e.contains("does not match"), "{e}");
    }
}
