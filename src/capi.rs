//! C interface (cargo feature `capi`): an opaque world handle, status codes and a thread-local
//! last-error message. The header `include/weft.h` is generated from this file by cbindgen
//! (`build.rs` writes it to `OUT_DIR` when the feature is on; `tests/capi.rs` checks that the
//! committed copy is up to date, and compiles and runs `examples/c/cloth.c` against it).
//!
//! Safety model: every function checks its pointers. A world handle is accepted only if it was
//! returned by [`weft_world_create`] and not yet destroyed (live handles are kept in a registry),
//! so a null, dangling, double-freed or made-up handle gives [`WeftStatus::InvalidHandle`]
//! instead of a crash. Buffers come with their length, which is checked. A Rust panic never
//! crosses the boundary: it is caught and returned as [`WeftStatus::Panic`]. One handle must not
//! be used from two threads at the same time (different handles may).

use std::cell::RefCell;
use std::collections::HashSet;
use std::ffi::{c_char, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Mutex;

use crate::{ClothDesc, Effects, Fabric, PinSpec, SolverParams, WeftError, World};

/// Result of every C call.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WeftStatus {
    /// Success.
    Ok = 0,
    /// A required pointer was null.
    NullPointer = 1,
    /// The world handle is null, unknown or already destroyed.
    InvalidHandle = 2,
    /// A parameter is out of range (message names it).
    InvalidArgument = 3,
    /// A buffer has the wrong length.
    BufferLength = 4,
    /// An index is out of range.
    IndexOutOfRange = 5,
    /// A step produced a non-finite value; the state before the step was kept.
    Diverged = 6,
    /// A Rust panic was caught at the boundary (a bug in weft; please report it).
    Panic = 7,
    /// Any other error (message says which).
    Other = 8,
}

/// Solver parameters for [`weft_world_create`]; get defaults from
/// [`weft_solver_params_default`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct WeftSolverParams {
    /// Time step of one step, s.
    pub dt: f32,
    /// Substeps per step.
    pub substeps: u32,
    /// Solver sweeps per substep.
    pub iterations: u32,
    /// Worker threads: 0 = all cores (global pool), k = own pool of k threads.
    pub threads: u32,
}

/// An opaque simulated world.
pub struct WeftWorld {
    world: World,
}

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

static LIVE: Mutex<Option<HashSet<usize>>> = Mutex::new(None);

fn live<R>(f: impl FnOnce(&mut HashSet<usize>) -> R) -> R {
    let mut g = LIVE.lock().unwrap_or_else(|p| p.into_inner());
    f(g.get_or_insert_with(HashSet::new))
}

fn set_error(msg: &str) {
    let c = CString::new(msg.replace('\0', " ")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = c);
}

fn status_of(e: &WeftError) -> WeftStatus {
    match e {
        WeftError::InvalidParameter { .. } | WeftError::InvalidMesh { .. } | WeftError::Scene(_) => WeftStatus::InvalidArgument,
        WeftError::BufferLength { .. } => WeftStatus::BufferLength,
        WeftError::IndexOutOfRange { .. } => WeftStatus::IndexOutOfRange,
        WeftError::Diverged { .. } => WeftStatus::Diverged,
        _ => WeftStatus::Other,
    }
}

type Fail = (WeftStatus, String);

fn fail(s: WeftStatus, msg: impl Into<String>) -> Fail {
    (s, msg.into())
}

impl From<WeftError> for Fail {
    fn from(e: WeftError) -> Fail {
        (status_of(&e), e.to_string())
    }
}

/// Runs `f` with the panic net and the error bookkeeping of every entry point.
fn boundary(f: impl FnOnce() -> Result<(), Fail>) -> WeftStatus {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => {
            set_error("");
            WeftStatus::Ok
        }
        Ok(Err((s, msg))) => {
            set_error(&msg);
            s
        }
        Err(p) => {
            let what = p
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            set_error(&format!("internal panic in weft: {what}"));
            WeftStatus::Panic
        }
    }
}

fn world_mut<'a>(h: *mut WeftWorld) -> Result<&'a mut World, Fail> {
    if h.is_null() || !live(|s| s.contains(&(h as usize))) {
        return Err(fail(WeftStatus::InvalidHandle, "invalid world handle (null, unknown or destroyed)"));
    }
    // SAFETY: the address is in the registry, so it came from `Box::into_raw` in
    // `weft_world_create` and has not been freed; callers must not share one handle across
    // threads concurrently (documented).
    Ok(unsafe { &mut (*h).world })
}

fn non_null<T>(p: *const T, name: &str) -> Result<(), Fail> {
    if p.is_null() {
        Err(fail(WeftStatus::NullPointer, format!("`{name}` is null")))
    } else {
        Ok(())
    }
}

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

/// Creates a world. `params` may be null (defaults); `gravity` points at 3 floats or is null
/// (no gravity). On success `*out` receives the handle; free it with [`weft_world_destroy`].
///
/// # Safety
/// Non-null pointers must point at valid, readable values (`gravity`: 3 floats) and `out` at a
/// writable handle slot.
#[no_mangle]
pub unsafe extern "C" fn weft_world_create(params: *const WeftSolverParams, gravity: *const f32, out: *mut *mut WeftWorld) -> WeftStatus {
    boundary(|| {
        non_null(out, "out")?;
        let mut p = SolverParams::default();
        if !params.is_null() {
            // SAFETY: non-null and, by the contract, valid.
            let c = unsafe { *params };
            (p.dt, p.substeps, p.iterations, p.threads) = (c.dt, c.substeps, c.iterations, c.threads as usize);
        }
        let mut effects = Effects::default();
        if !gravity.is_null() {
            // SAFETY: non-null and, by the contract, three readable floats.
            let g = unsafe { std::slice::from_raw_parts(gravity, 3) };
            effects.gravity = Some([g[0], g[1], g[2]]);
        }
        let world = World::new(p, effects)?;
        let h = Box::into_raw(Box::new(WeftWorld { world }));
        live(|s| s.insert(h as usize));
        // SAFETY: checked non-null; writable by the contract.
        unsafe { *out = h };
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
        non_null(origin, "origin")?;
        // SAFETY: non-null and three readable floats by the contract.
        let o = unsafe { std::slice::from_raw_parts(origin, 3) };
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
            origin: [o[0], o[1], o[2]],
            fabric,
            pins: if pin_corners { vec![PinSpec::FirstRowCorners] } else { Vec::new() },
            ..Default::default()
        };
        let k = w.add_cloth(&desc)?;
        if !out_cloth.is_null() {
            // SAFETY: non-null, writable by the contract.
            unsafe { *out_cloth = k as u32 };
        }
        Ok(())
    })
}

/// Advances the world by `dt` seconds.
///
/// # Safety
/// `world` must not be used concurrently from another thread.
#[no_mangle]
pub unsafe extern "C" fn weft_world_step(world: *mut WeftWorld, dt: f32) -> WeftStatus {
    boundary(|| Ok(world_mut(world)?.step(dt)?))
}

/// Writes the number of particles to `*out`.
///
/// # Safety
/// `out` must point at a writable `size_t`.
#[no_mangle]
pub unsafe extern "C" fn weft_world_particle_count(world: *mut WeftWorld, out: *mut usize) -> WeftStatus {
    boundary(|| {
        let w = world_mut(world)?;
        non_null(out, "out")?;
        // SAFETY: non-null, writable by the contract.
        unsafe { *out = w.particle_count() };
        Ok(())
    })
}

/// Copies positions, interleaved `x0 y0 z0 x1 ...`, into `out`, which holds `len` floats;
/// `len` must be exactly 3 times the particle count.
///
/// # Safety
/// `out` must point at `len` writable floats.
#[no_mangle]
pub unsafe extern "C" fn weft_world_copy_positions(world: *mut WeftWorld, out: *mut f32, len: usize) -> WeftStatus {
    boundary(|| {
        let w = world_mut(world)?;
        non_null(out, "out")?;
        let need = w.particle_count().saturating_mul(3);
        if len != need {
            return Err(WeftError::BufferLength {
                name: "positions",
                got: len,
                expected: need,
            }
            .into());
        }
        // SAFETY: non-null and `len` writable floats by the contract.
        let buf = unsafe { std::slice::from_raw_parts_mut(out, len) };
        Ok(w.read_positions(buf)?)
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

/// The message of the last failed call on this thread (empty after a success). The pointer is
/// valid until the next weft call on this thread; never null.
#[no_mangle]
pub extern "C" fn weft_last_error_message() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ptr())
}

/// Destroys a world. Null, unknown or already destroyed handles return `InvalidHandle` and
/// change nothing.
///
/// # Safety
/// `world` must not be in use on another thread.
#[no_mangle]
pub unsafe extern "C" fn weft_world_destroy(world: *mut WeftWorld) -> WeftStatus {
    boundary(|| {
        if world.is_null() || !live(|s| s.remove(&(world as usize))) {
            return Err(fail(WeftStatus::InvalidHandle, "invalid world handle (null, unknown or destroyed)"));
        }
        // SAFETY: was in the registry (from `Box::into_raw`), now removed: freed exactly once.
        drop(unsafe { Box::from_raw(world) });
        Ok(())
    })
}
