//! The C interface (feature `capi`; CI runs `cargo test --features capi --test capi`):
//! the committed header is what cbindgen generates, the C example compiles against it, links
//! the static library built with the feature, and runs; invalid input gives status codes.
#![cfg(feature = "capi")]

use std::path::{Path, PathBuf};
use std::process::Command;
use std::ptr::{null, null_mut};

use weft::capi::*;
use weft::WeftError;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn committed_header_is_up_to_date() {
    let generated = std::fs::read_to_string(concat!(env!("OUT_DIR"), "/weft.h")).unwrap();
    let committed = std::fs::read_to_string(root().join("include/weft.h")).unwrap_or_default();
    assert!(
        generated == committed,
        "include/weft.h is stale: copy {}/weft.h over it (the build script regenerates it from src/capi/)",
        env!("OUT_DIR")
    );
}

fn run(cmd: &mut Command) -> String {
    let out = cmd.output().unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e}"));
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{cmd:?} failed ({}):\n{text}", out.status);
    text
}

/// Whether `cc` can build and run a program with AddressSanitizer (gcc's or clang's libasan).
fn asan_available(cc: &str, dir: &Path) -> bool {
    let src = dir.join("asan_probe.c");
    let exe = dir.join("asan_probe");
    std::fs::write(&src, "int main(void) { return 0; }\n").unwrap();
    let built = Command::new(cc)
        .arg(&src)
        .args(["-fsanitize=address", "-o"])
        .arg(&exe)
        .output()
        .is_ok_and(|o| o.status.success());
    built && Command::new(&exe).output().is_ok_and(|o| o.status.success())
}

#[test]
fn c_examples_compile_link_and_run_also_under_address_sanitizer() {
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
    let cc = std::env::var("CC").unwrap_or_else(|_| "cc".into());
    // AddressSanitizer on the C side: the examples' own memory errors, and (through the
    // intercepted malloc and free, which the Rust side uses too) double frees, frees of
    // foreign pointers and leaks anywhere in the process. Opt out with WEFT_CAPI_NO_ASAN=1 on a
    // machine without libasan.
    let asan = std::env::var_os("WEFT_CAPI_NO_ASAN").is_none();
    if asan {
        assert!(
            asan_available(&cc, &target),
            "`{cc} -fsanitize=address` does not work here: install libasan (Debian: gcc's libasan8) or set WEFT_CAPI_NO_ASAN=1"
        );
    }
    let expect: [(&str, &[&str]); 2] = [
        ("cloth", &["ok: the cloth fell and the pin moved", "short buffer: status 4"]),
        (
            "scene",
            &[
                "ok: scene, obstacles, self-collision, advance, readback and snapshot",
                "replay identical",
                "WEFT_STATUS_SCENE -> 10: scene error: scene at line 2",
                "WEFT_STATUS_INVALID_MESH -> 9",
            ],
        ),
    ];
    for (name, wants) in expect {
        for sanitize in [false, true] {
            if sanitize && !asan {
                continue;
            }
            let exe = target.join(if sanitize { format!("{name}-asan") } else { name.to_string() });
            let mut cmd = Command::new(&cc);
            cmd.arg(root().join(format!("examples/c/{name}.c")))
                .arg("-I")
                .arg(root().join("include"))
                .args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-o"])
                .arg(&exe);
            if sanitize {
                cmd.args(["-fsanitize=address", "-fno-omit-frame-pointer", "-g"]);
            }
            run(cmd.arg(&lib).args(["-lpthread", "-ldl", "-lm"]));
            let out = run(Command::new(&exe).env("ASAN_OPTIONS", "detect_leaks=1:abort_on_error=0"));
            for want in wants {
                assert!(out.contains(want), "{name} (sanitizer {sanitize}) printed no `{want}`:\n{out}");
            }
            assert!(!out.contains("AddressSanitizer"), "{out}");
        }
    }
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

#[test]
fn every_error_kind_has_its_own_status_code() {
    let kinds = [
        (WeftError::param("x", 1, "why"), WeftStatus::InvalidArgument),
        (
            WeftError::InvalidMesh {
                source_name: None,
                reason: "r".into(),
            },
            WeftStatus::InvalidMesh,
        ),
        (WeftError::Diverged { particle: 0, stage: "s" }, WeftStatus::Diverged),
        (
            WeftError::BufferLength {
                name: "b",
                got: 1,
                expected: 2,
            },
            WeftStatus::BufferLength,
        ),
        (
            WeftError::IndexOutOfRange {
                name: "i",
                index: 3,
                len: 1,
            },
            WeftStatus::IndexOutOfRange,
        ),
        (WeftError::Scene("s".into()), WeftStatus::Scene),
        (
            WeftError::Io {
                path: "p".into(),
                message: "m".into(),
            },
            WeftStatus::Io,
        ),
    ];
    let mut seen = std::collections::HashSet::new();
    for (e, s) in kinds {
        assert_eq!(WeftStatus::of(&e), s, "{e}");
        assert!(seen.insert(s as i32), "two kinds share {s:?}");
    }
}

const SCENE: &str = r#"
[solver]
dt = 0.01
substeps = 4
[effects]
gravity = [0.0, -9.81, 0.0]
[[cloth]]
rows = 6
cols = 5
spacing = 0.05
origin = [0.0, 0.3, 0.0]
u = [1.0, 0.0, 0.0]
v = [0.0, 0.0, 1.0]
"#;

unsafe fn scene_world() -> *mut WeftWorld {
    let mut w = std::ptr::null_mut();
    assert_eq!(
        unsafe { weft_world_create_from_scene(SCENE.as_ptr().cast(), SCENE.len(), &mut w) },
        WeftStatus::Ok
    );
    w
}

/// A `threads = 0` world reports no choice before its trial's steps have run, one after.
#[test]
fn thread_choice_after_the_trial() {
    unsafe {
        let w = scene_world();
        let mut tc = WeftThreadChoice::default();
        assert_eq!(weft_world_thread_choice(w, &mut tc), WeftStatus::Ok);
        assert!(!tc.chosen && tc.pool_ms == 0.0 && tc.caller_ms == 0.0, "{tc:?}");
        for _ in 0..weft::world::threads::TRIAL_STEPS {
            assert_eq!(weft_world_step(w, 0.01), WeftStatus::Ok);
        }
        assert_eq!(weft_world_thread_choice(w, &mut tc), WeftStatus::Ok);
        assert!(tc.chosen && tc.pool_ms > 0.0 && tc.caller_ms > 0.0, "{tc:?}");
        assert_eq!(weft_world_thread_choice(w, null_mut()), WeftStatus::NullPointer);
        assert_eq!(weft_world_thread_choice(0x20 as *mut WeftWorld, &mut tc), WeftStatus::InvalidHandle);
        assert_eq!(weft_world_destroy(w), WeftStatus::Ok);
    }
}

#[test]
fn scene_text_is_checked_and_bounded() {
    unsafe {
        let mut w: *mut WeftWorld = 0x10 as *mut WeftWorld;
        assert_eq!(weft_world_create_from_scene(std::ptr::null(), 5, &mut w), WeftStatus::NullPointer);
        assert!(w.is_null(), "a failed create leaves a null_mut() handle");
        assert_eq!(
            weft_world_create_from_scene(SCENE.as_ptr().cast(), SCENE.len(), null_mut()),
            WeftStatus::NullPointer
        );
        let bytes = [0xffu8, 0xfe];
        assert_eq!(weft_world_create_from_scene(bytes.as_ptr().cast(), 2, &mut w), WeftStatus::Scene);
        assert!(message().contains("UTF-8"), "{}", message());
        let t = "[[cloth]]\nrows = 0\n";
        assert_eq!(weft_world_create_from_scene(t.as_ptr().cast(), t.len(), &mut w), WeftStatus::Scene);
        assert!(message().contains("line 2"), "{}", message());
        // Too long is refused before a byte is read (the pointer is not dereferenced).
        let one = [b' '];
        assert_eq!(
            weft_world_create_from_scene(one.as_ptr().cast(), WEFT_MAX_SCENE_BYTES + 1, &mut w),
            WeftStatus::InvalidArgument
        );
        // An empty scene is a world without particles; a length short of the text reads only
        // what it is given.
        assert_eq!(weft_world_create_from_scene(one.as_ptr().cast(), 0, &mut w), WeftStatus::Ok);
        let mut n = 9usize;
        assert_eq!(weft_world_particle_count(w, &mut n), WeftStatus::Ok);
        assert_eq!(n, 0);
        assert_eq!(weft_world_destroy(w), WeftStatus::Ok);
        let w = scene_world();
        assert_eq!(weft_world_particle_count(w, &mut n), WeftStatus::Ok);
        assert_eq!(n, 30);
        assert_eq!(weft_world_destroy(w), WeftStatus::Ok);
    }
}

#[test]
fn obstacles_are_validated_and_hold_the_cloth() {
    unsafe {
        let w = scene_world();
        let (p, up, c) = ([0.0f32, 0.0, 0.0], [0.0f32, 2.0, 0.0], [0.1f32, 0.1, 0.1]);
        let mut k = 99u32;
        assert_eq!(weft_world_add_plane(w, p.as_ptr(), up.as_ptr(), null(), &mut k), WeftStatus::Ok);
        assert_eq!(k, 0);
        assert_eq!(
            weft_world_add_plane(w, p.as_ptr(), [0.0f32; 3].as_ptr(), null(), null_mut()),
            WeftStatus::InvalidArgument
        );
        assert_eq!(
            weft_world_add_plane(w, null(), up.as_ptr(), null(), null_mut()),
            WeftStatus::NullPointer
        );
        assert_eq!(
            weft_world_add_sphere(w, c.as_ptr(), 0.0, null(), null_mut()),
            WeftStatus::InvalidArgument
        );
        assert_eq!(weft_world_add_sphere(w, null(), 1.0, null(), null_mut()), WeftStatus::NullPointer);
        let moving = WeftObstacleOptions {
            velocity: [0.0, 0.0, 0.1],
            has_friction: true,
            friction: 0.4,
        };
        assert_eq!(
            weft_world_add_sphere(w, [5.0f32, 5.0, 5.0].as_ptr(), 0.1, &moving, &mut k),
            WeftStatus::Ok
        );
        assert_eq!(k, 1);
        let bad = [
            WeftObstacleOptions {
                velocity: [f32::NAN, 0.0, 0.0],
                ..moving
            },
            WeftObstacleOptions { friction: -1.0, ..moving },
        ];
        for b in &bad {
            assert_eq!(
                weft_world_add_sphere(w, c.as_ptr(), 0.1, b, null_mut()),
                WeftStatus::InvalidArgument
            );
        }
        let far = [5.0f32, 6.0, 5.0];
        assert_eq!(
            weft_world_add_capsule(w, [5.0f32, 5.0, 5.0].as_ptr(), far.as_ptr(), 0.05, null(), &mut k),
            WeftStatus::Ok
        );
        assert_eq!(k, 2);
        assert_eq!(
            weft_world_add_capsule(w, c.as_ptr(), null(), 0.05, null(), null_mut()),
            WeftStatus::NullPointer
        );
        assert_eq!(
            weft_world_add_capsule(w, c.as_ptr(), far.as_ptr(), f32::NAN, null(), null_mut()),
            WeftStatus::InvalidArgument
        );
        let (bc, half, rot) = ([-5.0f32, 5.0, 0.0], [0.1f32, 0.2, 0.3], [0.0f32, 45.0, 0.0]);
        assert_eq!(
            weft_world_add_box(w, bc.as_ptr(), half.as_ptr(), rot.as_ptr(), null(), &mut k),
            WeftStatus::Ok
        );
        assert_eq!(k, 3);
        assert_eq!(
            weft_world_add_box(w, bc.as_ptr(), half.as_ptr(), null(), null(), null_mut()),
            WeftStatus::Ok
        );
        let inf = [0.0f32, f32::INFINITY, 0.0];
        assert_eq!(
            weft_world_add_box(w, bc.as_ptr(), half.as_ptr(), inf.as_ptr(), null(), null_mut()),
            WeftStatus::InvalidArgument
        );
        assert_eq!(
            weft_world_add_box(w, bc.as_ptr(), [0.1f32, 0.0, 0.1].as_ptr(), null(), null(), null_mut()),
            WeftStatus::InvalidArgument
        );
        // A mesh: a quad far away; bad shapes of arrays, indices and broadphase values.
        let v = [9.0f32, 0.0, 9.0, 10.0, 0.0, 9.0, 10.0, 0.0, 10.0, 9.0, 0.0, 10.0];
        let f = [0u32, 2, 1, 0, 3, 2];
        for bp in [WeftMeshBroadphase::Grid, WeftMeshBroadphase::Bvh, WeftMeshBroadphase::Hash] {
            assert_eq!(
                weft_world_add_mesh(w, v.as_ptr(), 12, f.as_ptr(), 6, bp as u32, true, null(), null_mut()),
                WeftStatus::Ok
            );
        }
        assert_eq!(
            weft_world_add_mesh(w, v.as_ptr(), 12, f.as_ptr(), 6, 3, false, null(), null_mut()),
            WeftStatus::InvalidArgument
        );
        assert_eq!(
            weft_world_add_mesh(w, v.as_ptr(), 12, f.as_ptr(), 5, 0, false, null(), null_mut()),
            WeftStatus::BufferLength
        );
        assert_eq!(
            weft_world_add_mesh(w, null(), 12, f.as_ptr(), 6, 0, false, null(), null_mut()),
            WeftStatus::NullPointer
        );
        assert_eq!(
            weft_world_add_mesh(w, v.as_ptr(), 12, null(), 6, 0, false, null(), null_mut()),
            WeftStatus::NullPointer
        );
        assert_eq!(
            weft_world_add_mesh(w, v.as_ptr(), usize::MAX, f.as_ptr(), 6, 0, false, null(), null_mut()),
            WeftStatus::InvalidArgument
        );
        assert_eq!(
            weft_world_add_mesh(w, v.as_ptr(), 0, f.as_ptr(), 0, 0, false, null(), null_mut()),
            WeftStatus::InvalidMesh
        );
        let flat = [0u32, 0, 1];
        assert_eq!(
            weft_world_add_mesh(w, v.as_ptr(), 12, flat.as_ptr(), 3, 0, false, null(), null_mut()),
            WeftStatus::InvalidMesh
        );
        let nan = [f32::NAN; 9];
        assert_eq!(
            weft_world_add_mesh(w, nan.as_ptr(), 9, f.as_ptr(), 3, 0, false, null(), null_mut()),
            WeftStatus::InvalidMesh
        );
        assert_eq!(weft_world_set_friction(w, -0.1), WeftStatus::InvalidArgument);
        assert_eq!(weft_world_set_friction(w, 0.2), WeftStatus::Ok);
        assert_eq!(
            weft_world_add_sphere(0x20 as *mut WeftWorld, c.as_ptr(), 1.0, null(), null_mut()),
            WeftStatus::InvalidHandle
        );
        // The cloth (y = 0.3) falls onto the plane y = 0 and lies on it, the other obstacles far away.
        for _ in 0..60 {
            assert_eq!(weft_world_advance(w, 0.01, null_mut()), WeftStatus::Ok);
        }
        let mut pos = vec![0.0f32; 90];
        assert_eq!(weft_world_copy_positions(w, pos.as_mut_ptr(), 90), WeftStatus::Ok);
        let ys: Vec<f32> = pos.chunks(3).map(|q| q[1]).collect();
        assert!(ys.iter().all(|&y| (0.0..0.01).contains(&y)), "{ys:?}");
        assert_eq!(weft_world_destroy(w), WeftStatus::Ok);
    }
}

#[test]
fn self_collision_advance_readback_and_snapshots() {
    unsafe {
        let w = scene_world();
        let d = weft_self_collision_default();
        assert_eq!(
            (d.response, d.broadphase, d.distance, d.travel),
            (WeftResponse::Vccpbd as u32, WeftSelfBroadphase::Hash as u32, 0.0, 1.0)
        );
        for (r, b) in [(0, 0), (1, 1), (2, 1)] {
            let c = WeftSelfCollision {
                response: r,
                broadphase: b,
                distance: 0.02,
                ..d
            };
            assert_eq!(weft_world_set_self_collision(w, &c), WeftStatus::Ok);
        }
        for bad in [
            WeftSelfCollision { response: 3, ..d },
            WeftSelfCollision { broadphase: 2, ..d },
            WeftSelfCollision { distance: -0.1, ..d },
            WeftSelfCollision { friction: 1.5, ..d },
            WeftSelfCollision { friction: f32::NAN, ..d },
            WeftSelfCollision { travel: 0.0, ..d },
            WeftSelfCollision { travel: 2.5, ..d },
        ] {
            assert_eq!(weft_world_set_self_collision(w, &bad), WeftStatus::InvalidArgument);
        }
        assert_eq!(
            weft_world_set_self_collision(w, std::ptr::null()),
            WeftStatus::Ok,
            "null turns it off"
        );
        assert_eq!(weft_world_set_self_collision(w, &d), WeftStatus::Ok);

        // Advance: 2.5 steps of time takes 2 and leaves alpha 0.5; the cap drops whole steps.
        let mut r = WeftAdvanceReport::default();
        assert_eq!(weft_world_advance(w, 0.025, &mut r), WeftStatus::Ok);
        assert_eq!((r.steps, r.capped), (2, false));
        assert!((r.alpha - 0.5).abs() < 1e-4, "{}", r.alpha);
        assert_eq!(weft_world_set_max_steps_per_advance(w, 0), WeftStatus::InvalidArgument);
        assert_eq!(weft_world_set_max_steps_per_advance(w, 3), WeftStatus::Ok);
        assert_eq!(weft_world_advance(w, 0.1, &mut r), WeftStatus::Ok);
        assert_eq!((r.steps, r.capped), (3, true));
        assert!(r.dropped_time > 0.06, "{}", r.dropped_time);
        assert_eq!(weft_world_advance(w, f64::NAN, null_mut()), WeftStatus::InvalidArgument);
        let mut steps = 0u64;
        assert_eq!(weft_world_steps(w, &mut steps), WeftStatus::Ok);
        assert_eq!(steps, 5);
        assert_eq!(weft_world_steps(w, null_mut()), WeftStatus::NullPointer);

        // Interpolation: alpha 1 is now; alpha 0 the state before the last step.
        let mut now = vec![0.0f32; 90];
        let mut at1 = vec![0.0f32; 90];
        let mut at0 = vec![0.0f32; 90];
        assert_eq!(weft_world_copy_positions(w, now.as_mut_ptr(), 90), WeftStatus::Ok);
        assert_eq!(weft_world_copy_interpolated_positions(w, 1.0, at1.as_mut_ptr(), 90), WeftStatus::Ok);
        assert_eq!(weft_world_copy_interpolated_positions(w, 0.0, at0.as_mut_ptr(), 90), WeftStatus::Ok);
        // `x_prev + 1 (x - x_prev)` may differ from `x` in the last bit.
        assert!(now.iter().zip(&at1).all(|(a, b)| (a - b).abs() <= 1e-6), "{now:?} {at1:?}");
        assert!(at0.iter().zip(&now).any(|(a, b)| a != b), "the cloth moved in the last step");
        assert_eq!(
            weft_world_copy_interpolated_positions(w, 1.5, at0.as_mut_ptr(), 90),
            WeftStatus::InvalidArgument
        );
        assert_eq!(
            weft_world_copy_interpolated_positions(w, 0.5, at0.as_mut_ptr(), 87),
            WeftStatus::BufferLength
        );
        assert_eq!(
            weft_world_copy_interpolated_positions(w, 0.5, null_mut(), 90),
            WeftStatus::NullPointer
        );

        // Normals and triangles.
        let mut nrm = vec![0.0f32; 90];
        assert_eq!(weft_world_copy_normals(w, nrm.as_mut_ptr(), 90), WeftStatus::Ok);
        for q in nrm.chunks(3) {
            let l = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
            assert!((l - 1.0).abs() < 1e-4, "{q:?}");
        }
        assert_eq!(weft_world_copy_normals(w, nrm.as_mut_ptr(), 91), WeftStatus::BufferLength);
        let mut nt = 0usize;
        assert_eq!(weft_world_triangle_count(w, &mut nt), WeftStatus::Ok);
        assert_eq!(nt, 2 * 5 * 4);
        assert_eq!(weft_world_triangle_count(w, null_mut()), WeftStatus::NullPointer);
        let mut tri = vec![u32::MAX; 3 * nt];
        assert_eq!(weft_world_copy_triangles(w, tri.as_mut_ptr(), 3 * nt - 1), WeftStatus::BufferLength);
        assert_eq!(weft_world_copy_triangles(w, tri.as_mut_ptr(), 3 * nt), WeftStatus::Ok);
        assert!(tri.iter().all(|&i| i < 30));
        assert_eq!(
            tri[..],
            weft::scene::Scene::parse(SCENE, "s").unwrap().world().unwrap().triangles().concat()[..]
        );

        // Snapshot, run on, restore, run the same again: the same bits.
        let mut s: *mut WeftSnapshot = null_mut();
        assert_eq!(weft_world_snapshot(w, null_mut()), WeftStatus::NullPointer);
        assert_eq!(weft_world_snapshot(w, &mut s), WeftStatus::Ok);
        let run_on = |pos: &mut Vec<f32>| {
            for _ in 0..7 {
                assert_eq!(weft_world_advance(w, 0.013, null_mut()), WeftStatus::Ok);
            }
            assert_eq!(weft_world_copy_positions(w, pos.as_mut_ptr(), 90), WeftStatus::Ok);
        };
        let (mut a, mut b) = (vec![0.0f32; 90], vec![0.0f32; 90]);
        run_on(&mut a);
        assert_eq!(weft_world_restore(w, s), WeftStatus::Ok);
        assert_eq!(weft_world_steps(w, &mut steps), WeftStatus::Ok);
        assert_eq!(steps, 5);
        run_on(&mut b);
        assert_eq!(
            a.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            b.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        );
        assert_ne!(a, now, "the cloth moved after the snapshot");

        // A snapshot of another particle count is refused; handles are checked; a snapshot
        // outlives its world.
        let mut other: *mut WeftWorld = null_mut();
        assert_eq!(weft_world_create(std::ptr::null(), std::ptr::null(), &mut other), WeftStatus::Ok);
        assert_eq!(weft_world_restore(other, s), WeftStatus::BufferLength);
        assert_eq!(weft_world_restore(w, std::ptr::null()), WeftStatus::InvalidHandle);
        assert_eq!(weft_world_restore(w, 0x30 as *const WeftSnapshot), WeftStatus::InvalidHandle);
        assert_eq!(
            weft_world_restore(w, w.cast()),
            WeftStatus::InvalidHandle,
            "a world is not a snapshot"
        );
        assert_eq!(weft_snapshot_destroy(w.cast()), WeftStatus::InvalidHandle);
        assert_eq!(weft_world_destroy(s.cast()), WeftStatus::InvalidHandle, "a snapshot is not a world");
        assert_eq!(weft_world_reset(w), WeftStatus::Ok);
        assert_eq!(weft_world_steps(w, &mut steps), WeftStatus::Ok);
        assert_eq!(steps, 0, "reset goes back to before the first step");
        assert_eq!(weft_world_destroy(w), WeftStatus::Ok);
        let w = scene_world();
        assert_eq!(
            weft_world_restore(w, s),
            WeftStatus::Ok,
            "restored onto a new world of the same scene"
        );
        assert_eq!(weft_world_steps(w, &mut steps), WeftStatus::Ok);
        assert_eq!(steps, 5);
        assert_eq!(weft_snapshot_destroy(s), WeftStatus::Ok);
        assert_eq!(weft_snapshot_destroy(s), WeftStatus::InvalidHandle);
        assert_eq!(weft_snapshot_destroy(null_mut()), WeftStatus::InvalidHandle);
        assert_eq!(weft_world_restore(w, s), WeftStatus::InvalidHandle);
        assert_eq!(weft_world_destroy(w), WeftStatus::Ok);
        assert_eq!(weft_world_destroy(other), WeftStatus::Ok);
    }
}

/// Two cloths with a distance that would pair every particle of one with every particle of
/// the other: the step succeeds without self-collision and the count says so.
#[test]
fn self_collision_failed_steps_count_the_refused_lists() {
    let sheet = |y: f32| {
        format!("[[cloth]]\nrows = 30\ncols = 30\nspacing = 0.01\norigin = [0.0, {y}, 0.0]\nu = [1.0, 0.0, 0.0]\nv = [0.0, 0.0, 1.0]\n")
    };
    unsafe {
        for (distance, failed) in [(0.01, 0u64), (1.0, 1)] {
            let text = format!("[effects.self_collision]\ndistance = {distance}\n{}{}", sheet(1.0), sheet(1.02));
            let mut w = std::ptr::null_mut();
            assert_eq!(
                weft_world_create_from_scene(text.as_ptr().cast(), text.len(), &mut w),
                WeftStatus::Ok
            );
            assert_eq!(weft_world_step(w, 1.0 / 60.0), WeftStatus::Ok);
            let mut n = u64::MAX;
            assert_eq!(weft_world_self_collision_failed_steps(w, &mut n), WeftStatus::Ok);
            assert_eq!(n, failed, "distance {distance}");
            assert_eq!(weft_world_self_collision_failed_steps(w, null_mut()), WeftStatus::NullPointer);
            assert_eq!(weft_world_destroy(w), WeftStatus::Ok);
        }
    }
}
