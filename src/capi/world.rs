//! Worlds: creating them (from parameters or scene text), cloth, time, pins, snapshots,
//! destroying them, and the last error.

use super::*;

/// The default solver parameters (1/60 s, 8 substeps, 1 iteration, all cores).
#[no_mangle]
pub extern "C" fn weft_solver_params_default() -> WeftSolverParams {
    let d = SolverParams::default();
    WeftSolverParams {
        dt: d.dt,
        substeps: d.substeps,
        iterations: d.iterations,
        threads: d.threads as u32,
    }
}

/// Creates an empty world. `params` may be null (defaults); `gravity` points at 3 floats or is
/// null (no gravity). On success `*out` receives the handle (on failure, null); free it with
/// [`weft_world_destroy`].
///
/// # Safety
/// Non-null pointers must point at valid, readable values (`gravity`: 3 floats) and `out` at a
/// writable handle slot.
#[no_mangle]
pub unsafe extern "C" fn weft_world_create(params: *const WeftSolverParams, gravity: *const f32, out: *mut *mut WeftWorld) -> WeftStatus {
    boundary(|| {
        // SAFETY: `out` is writable by the contract.
        unsafe { put(out, std::ptr::null_mut(), "out") }?;
        let mut p = SolverParams::default();
        if !params.is_null() {
            // SAFETY: non-null and, by the contract, valid.
            let c = unsafe { *params };
            (p.dt, p.substeps, p.iterations, p.threads) = (c.dt, c.substeps, c.iterations, c.threads as usize);
        }
        let mut effects = Effects::default();
        if !gravity.is_null() {
            // SAFETY: non-null and, by the contract, three readable floats.
            effects.gravity = Some(unsafe { vec3(gravity, "gravity") }?);
        }
        let world = World::new(p, effects)?;
        // SAFETY: `out` checked non-null above.
        unsafe { register_world(world, out) };
        Ok(())
    })
}

/// Creates a world from scene text: `len` bytes of UTF-8 TOML at `text` (no terminating NUL
/// needed; at most [`WEFT_MAX_SCENE_BYTES`]), the format of `weft run` scene files (solver,
/// effects including self-collision, cloths, obstacles, strands). Mesh files a scene names are
/// read relative to the working directory. On success `*out` receives the handle (on failure,
/// null; the message gives the line and column); free it with [`weft_world_destroy`].
///
/// # Safety
/// `text` must point at `len` readable bytes and `out` at a writable handle slot.
#[no_mangle]
pub unsafe extern "C" fn weft_world_create_from_scene(text: *const c_char, len: usize, out: *mut *mut WeftWorld) -> WeftStatus {
    boundary(|| {
        // SAFETY: `out` is writable by the contract.
        unsafe { put(out, std::ptr::null_mut(), "out") }?;
        if len > WEFT_MAX_SCENE_BYTES {
            return Err(fail(
                WeftStatus::InvalidArgument,
                format!("scene text is {len} bytes; at most {WEFT_MAX_SCENE_BYTES} are accepted"),
            ));
        }
        // SAFETY: `len` readable bytes by the contract.
        let bytes = unsafe { input(text.cast::<u8>(), len, "text") }?;
        let text = std::str::from_utf8(bytes).map_err(|e| fail(WeftStatus::Scene, format!("scene text is not UTF-8: {e}")))?;
        let world = Scene::parse(text, "scene")?.world()?;
        // SAFETY: `out` checked non-null above.
        unsafe { register_world(world, out) };
        Ok(())
    })
}

/// Adds a `rows x cols` cloth with grid `spacing` (m) whose first particle is at `origin`
/// (3 floats), hanging along -y from a row along +x. `preset` is a fabric preset name
/// (`basic`, `cotton`, `wool`, `polyester`; null = `basic`). With `pin_corners` the two corners
/// of the first row are pinned. `out_cloth` (may be null) receives the cloth index.
///
/// # Safety
/// `origin` must point at 3 readable floats; `preset`, if non-null, at a NUL-terminated string;
/// `out_cloth`, if non-null, at a writable `uint32_t`.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn weft_world_add_cloth(
    world: *mut WeftWorld,
    rows: u32,
    cols: u32,
    spacing: f32,
    origin: *const f32,
    preset: *const c_char,
    pin_corners: bool,
    out_cloth: *mut u32,
) -> WeftStatus {
    boundary(|| {
        let w = world_mut(world)?;
        // SAFETY: three readable floats by the contract.
        let o = unsafe { vec3(origin, "origin") }?;
        let fabric = if preset.is_null() {
            Fabric::default()
        } else {
            // SAFETY: non-null, NUL-terminated by the contract.
            let name = unsafe { CStr::from_ptr(preset) }
                .to_str()
                .map_err(|_| fail(WeftStatus::InvalidArgument, "preset name is not UTF-8"))?;
            Fabric::preset(name)?
        };
        let desc = ClothDesc {
            rows,
            cols,
            spacing,
            origin: o,
            fabric,
            pins: if pin_corners { vec![PinSpec::FirstRowCorners] } else { Vec::new() },
            ..Default::default()
        };
        let k = w.add_cloth(&desc)?;
        // SAFETY: writable if non-null by the contract.
        unsafe { put_opt(out_cloth, k as u32) };
        Ok(())
    })
}

/// Advances the world by one step of `dt` seconds (however long; [`weft_world_advance`] keeps
/// the step length fixed instead).
///
/// # Safety
/// `world` must not be used concurrently from another thread.
#[no_mangle]
pub unsafe extern "C" fn weft_world_step(world: *mut WeftWorld, dt: f32) -> WeftStatus {
    boundary(|| Ok(world_mut(world)?.step(dt)?))
}

/// Adds `frame_dt` seconds of display time (finite, >= 0) and takes the whole fixed steps of
/// the solver's `dt` it owes (at most the cap of [`weft_world_set_max_steps_per_advance`],
/// default 8; whole steps beyond it are dropped and reported). `report` (may be null) receives
/// what was done, including the blend factor for
/// [`weft_world_copy_interpolated_positions`]. If a step fails the steps before it stand.
///
/// # Safety
/// `report`, if non-null, must point at a writable [`WeftAdvanceReport`].
#[no_mangle]
pub unsafe extern "C" fn weft_world_advance(world: *mut WeftWorld, frame_dt: f64, report: *mut WeftAdvanceReport) -> WeftStatus {
    boundary(|| {
        let r = world_mut(world)?.advance(frame_dt)?;
        let c = WeftAdvanceReport {
            steps: r.steps,
            capped: r.capped,
            dropped_time: r.dropped_time,
            alpha: r.alpha,
        };
        // SAFETY: writable if non-null by the contract.
        unsafe { put_opt(report, c) };
        Ok(())
    })
}

/// Sets the most fixed steps one [`weft_world_advance`] call may take (at least 1).
///
/// # Safety
/// `world` must not be used concurrently from another thread.
#[no_mangle]
pub unsafe extern "C" fn weft_world_set_max_steps_per_advance(world: *mut WeftWorld, max: u32) -> WeftStatus {
    boundary(|| Ok(world_mut(world)?.set_max_steps_per_advance(max)?))
}

/// Writes the number of steps taken so far to `*out`.
///
/// # Safety
/// `out` must point at a writable `uint64_t`.
#[no_mangle]
pub unsafe extern "C" fn weft_world_steps(world: *mut WeftWorld, out: *mut u64) -> WeftStatus {
    boundary(|| {
        let w = world_mut(world)?;
        // SAFETY: writable by the contract.
        unsafe { put(out, w.steps(), "out") }
    })
}

/// Writes where the steps of a `threads = 0` world run to `*out`: the global pool or the
/// calling thread, whichever the world's last trial measured faster (`chosen` false for other
/// thread settings and before the first trial has ended).
///
/// # Safety
/// `out` must point at a writable `WeftThreadChoice`.
#[no_mangle]
pub unsafe extern "C" fn weft_world_thread_choice(world: *mut WeftWorld, out: *mut WeftThreadChoice) -> WeftStatus {
    boundary(|| {
        let w = world_mut(world)?;
        let c = w.thread_choice().map_or(WeftThreadChoice::default(), |c| WeftThreadChoice {
            chosen: true,
            caller_thread: c.caller_thread,
            pool_ms: c.pool_ms,
            caller_ms: c.caller_ms,
        });
        // SAFETY: writable by the contract.
        unsafe { put(out, c, "out") }
    })
}

/// Moves pinned particle `index` to `(x, y, z)` over the next step (kinematic pin).
///
/// # Safety
/// `world` must not be used concurrently from another thread.
#[no_mangle]
pub unsafe extern "C" fn weft_world_set_pin_position(world: *mut WeftWorld, index: usize, x: f32, y: f32, z: f32) -> WeftStatus {
    boundary(|| Ok(world_mut(world)?.set_pin_position(index, mint::Point3 { x, y, z })?))
}

/// Copies the world's evolving state (positions, velocities, pins, time, the advance
/// accumulator) into a new snapshot; `*out` receives its handle (on failure, null). The
/// snapshot is independent of the world: free it with [`weft_snapshot_destroy`], before or
/// after the world.
///
/// # Safety
/// `out` must point at a writable handle slot.
#[no_mangle]
pub unsafe extern "C" fn weft_world_snapshot(world: *mut WeftWorld, out: *mut *mut WeftSnapshot) -> WeftStatus {
    boundary(|| {
        // SAFETY: writable by the contract.
        unsafe { put(out, std::ptr::null_mut(), "out") }?;
        let snapshot = world_mut(world)?.snapshot();
        let h = Box::into_raw(Box::new(WeftSnapshot { snapshot }));
        live(&SNAPSHOTS, |s| s.insert(h as usize));
        // SAFETY: checked non-null above, writable by the contract.
        unsafe { out.write(h) };
        Ok(())
    })
}

/// Puts the world back into the state of `snapshot` (taken from this world, or one with the
/// same particles); the run then continues bit for bit as from the moment it was taken. A
/// snapshot of another particle count gives [`WeftStatus::BufferLength`] and changes nothing.
/// The snapshot stays valid and can be restored again.
///
/// # Safety
/// `world` must not be used concurrently from another thread.
#[no_mangle]
pub unsafe extern "C" fn weft_world_restore(world: *mut WeftWorld, snapshot: *const WeftSnapshot) -> WeftStatus {
    boundary(|| {
        let w = world_mut(world)?;
        Ok(w.restore_snapshot(snapshot_ref(snapshot)?)?)
    })
}

/// Back to the state before the first step since the last cloth was added.
///
/// # Safety
/// `world` must not be used concurrently from another thread.
#[no_mangle]
pub unsafe extern "C" fn weft_world_reset(world: *mut WeftWorld) -> WeftStatus {
    boundary(|| Ok(world_mut(world)?.reset()?))
}

/// Frees a snapshot. Null, unknown or already freed handles return `InvalidHandle` and change
/// nothing.
///
/// # Safety
/// `snapshot` must not be in use on another thread.
#[no_mangle]
pub unsafe extern "C" fn weft_snapshot_destroy(snapshot: *mut WeftSnapshot) -> WeftStatus {
    boundary(|| {
        if snapshot.is_null() || !live(&SNAPSHOTS, |s| s.remove(&(snapshot as usize))) {
            return Err(bad_handle("snapshot"));
        }
        // SAFETY: was in the registry (from `Box::into_raw`), now removed: freed exactly once.
        drop(unsafe { Box::from_raw(snapshot) });
        Ok(())
    })
}

/// The message of the last failed call on this thread (empty after a success). The pointer is
/// valid until the next weft call on this thread; never null. weft owns it: do not free it.
#[no_mangle]
pub extern "C" fn weft_last_error_message() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ptr())
}

/// Destroys a world. Null, unknown or already destroyed handles return `InvalidHandle` and
/// change nothing. Snapshots taken from it stay valid.
///
/// # Safety
/// `world` must not be in use on another thread.
#[no_mangle]
pub unsafe extern "C" fn weft_world_destroy(world: *mut WeftWorld) -> WeftStatus {
    boundary(|| {
        if world.is_null() || !live(&WORLDS, |s| s.remove(&(world as usize))) {
            return Err(bad_handle("world"));
        }
        // SAFETY: was in the registry (from `Box::into_raw`), now removed: freed exactly once.
        drop(unsafe { Box::from_raw(world) });
        Ok(())
    })
}
