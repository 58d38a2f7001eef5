//! The C interface (feature `capi`; CI runs `cargo test --features capi --test capi`):
//! the committed header is what cbindgen generates, the C example compiles against it, links
//! the static library built with the feature, and runs; invalid input gives status codes.
#![cfg(feature = "capi")]

use std::path::{Path, PathBuf};
use std::process::Command;

use weft::capi::*;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn committed_header_is_up_to_date() {
    let generated = std::fs::read_to_string(concat!(env!("OUT_DIR"), "/weft.h")).unwrap();
    let committed = std::fs::read_to_string(root().join("include/weft.h")).unwrap_or_default();
    assert!(
        generated == committed,
        "include/weft.h is stale: copy {}/weft.h over it (the build script regenerates it from src/capi.rs)",
        env!("OUT_DIR")
    );
}

fn run(cmd: &mut Command) -> String {
    let out = cmd.output().unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e}"));
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{cmd:?} failed ({}):\n{text}", out.status);
    text
}

#[test]
fn c_example_compiles_links_and_runs() {
    // Build the static library with the feature in a target directory of its own (the outer
    // cargo holds the lock on the main one).
    let target = Path::new(env!("CARGO_TARGET_TMPDIR")).join("capi");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    run(Command::new(cargo)
        .current_dir(root())
        .args(["rustc", "--lib", "--features", "capi", "--crate-type", "staticlib", "--target-dir"])
        .arg(&target));
    let lib = target.join("debug/libweft.a");
    assert!(lib.exists(), "{} was not built", lib.display());
    let exe = target.join("cloth");
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    run(Command::new(cc)
        .arg(root().join("examples/c/cloth.c"))
        .arg("-I")
        .arg(root().join("include"))
        .args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-o"])
        .arg(&exe)
        .arg(&lib)
        .args(["-lpthread", "-ldl", "-lm"]));
    let out = run(&mut Command::new(&exe));
    assert!(out.contains("ok: the cloth fell and the pin moved"), "{out}");
    assert!(out.contains("short buffer: status 4"), "{out}");
}

fn message() -> String {
    // SAFETY: never null, NUL-terminated, valid until the next call on this thread.
    unsafe { std::ffi::CStr::from_ptr(weft_last_error_message()) }
        .to_string_lossy()
        .into_owned()
}

#[test]
fn bad_handles_pointers_and_lengths_are_status_codes() {
    let mut w: *mut WeftWorld = std::ptr::null_mut();
    let g = [0.0f32, -9.81, 0.0];
    let o = [0.0f32, 1.0, 0.0];
    unsafe {
        assert_eq!(
            weft_world_create(std::ptr::null(), g.as_ptr(), std::ptr::null_mut()),
            WeftStatus::NullPointer
        );
        let bad = WeftSolverParams {
            dt: -1.0,
            ..weft_solver_params_default()
        };
        assert_eq!(weft_world_create(&bad, g.as_ptr(), &mut w), WeftStatus::InvalidArgument);
        assert!(message().contains("solver.dt"), "{}", message());
        assert_eq!(weft_world_create(std::ptr::null(), g.as_ptr(), &mut w), WeftStatus::Ok);
        assert_eq!(message(), "");
        assert_eq!(
            weft_world_add_cloth(w, 0, 4, 0.1, o.as_ptr(), std::ptr::null(), true, std::ptr::null_mut()),
            WeftStatus::InvalidArgument
        );
        assert_eq!(
            weft_world_add_cloth(w, 4, 4, 0.1, std::ptr::null(), std::ptr::null(), true, std::ptr::null_mut()),
            WeftStatus::NullPointer
        );
        let bytes = [0xffu8, 0];
        assert_eq!(
            weft_world_add_cloth(w, 4, 4, 0.1, o.as_ptr(), bytes.as_ptr().cast(), true, std::ptr::null_mut()),
            WeftStatus::InvalidArgument
        );
        let mut k = 7u32;
        assert_eq!(
            weft_world_add_cloth(w, 4, 5, 0.1, o.as_ptr(), c"wool".as_ptr(), true, &mut k),
            WeftStatus::Ok
        );
        assert_eq!(k, 0);
        let mut n = 0usize;
        assert_eq!(weft_world_particle_count(w, &mut n), WeftStatus::Ok);
        assert_eq!(n, 20);
        assert_eq!(weft_world_particle_count(w, std::ptr::null_mut()), WeftStatus::NullPointer);
        let mut buf = vec![0.0f32; 3 * n];
        assert_eq!(weft_world_copy_positions(w, buf.as_mut_ptr(), 3 * n - 3), WeftStatus::BufferLength);
        assert!(message().contains("expected 60"), "{}", message());
        assert_eq!(weft_world_copy_positions(w, buf.as_mut_ptr(), 3 * n), WeftStatus::Ok);
        assert_eq!(&buf[..3], &[0.0, 1.0, 0.0]);
        assert_eq!(
            weft_world_set_pin_position(w, 1, 0.0, 0.0, 0.0),
            WeftStatus::InvalidArgument,
            "particle 1 is free"
        );
        assert_eq!(weft_world_set_pin_position(w, 999, 0.0, 0.0, 0.0), WeftStatus::IndexOutOfRange);
        assert_eq!(weft_world_set_pin_position(w, 0, f32::NAN, 0.0, 0.0), WeftStatus::InvalidArgument);
        assert_eq!(weft_world_step(w, f32::INFINITY), WeftStatus::InvalidArgument);
        assert_eq!(weft_world_step(w, 0.01), WeftStatus::Ok);
        // A made-up handle and a destroyed one are refused without being dereferenced.
        let fake = 0x1000 as *mut WeftWorld;
        assert_eq!(weft_world_step(fake, 0.01), WeftStatus::InvalidHandle);
        assert_eq!(weft_world_destroy(fake), WeftStatus::InvalidHandle);
        assert_eq!(weft_world_destroy(w), WeftStatus::Ok);
        assert_eq!(weft_world_step(w, 0.01), WeftStatus::InvalidHandle);
        assert_eq!(weft_world_copy_positions(w, buf.as_mut_ptr(), 3 * n), WeftStatus::InvalidHandle);
        assert_eq!(weft_world_destroy(w), WeftStatus::InvalidHandle);
        assert_eq!(weft_world_destroy(std::ptr::null_mut()), WeftStatus::InvalidHandle);
    }
}
