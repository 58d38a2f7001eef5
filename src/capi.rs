//! C interface (cargo feature `capi`): opaque world and snapshot handles, status codes and a
//! thread-local last-error message. The header `include/weft.h` is generated from this file by
//! cbindgen (`build.rs` writes it to `OUT_DIR` when the feature is on; `tests/capi.rs` checks
//! that the committed copy is up to date, and compiles and runs the programs in `examples/c/`
//! against it).
//!
//! The functions, by group:
//!
//! - world: [`weft_world_create`], [`weft_world_create_from_scene`] (scene TOML text),
//!   [`weft_world_add_cloth`], [`weft_world_destroy`];
//! - obstacles: [`weft_world_add_plane`], [`weft_world_add_sphere`], [`weft_world_add_capsule`],
//!   [`weft_world_add_box`], [`weft_world_add_mesh`] (vertex and index arrays), each with an
//!   optional [`WeftObstacleOptions`] (velocity, own friction); [`weft_world_set_friction`];
//! - self-collision: [`weft_self_collision_default`], [`weft_world_set_self_collision`];
//! - time: [`weft_world_step`] (one step of a given length), [`weft_world_advance`] (frame time
//!   into fixed steps), [`weft_world_set_max_steps_per_advance`], [`weft_world_steps`];
//! - input: [`weft_world_set_pin_position`];
//! - readback into caller buffers: [`weft_world_particle_count`], [`weft_world_copy_positions`],
//!   [`weft_world_copy_interpolated_positions`], [`weft_world_copy_normals`],
//!   [`weft_world_triangle_count`], [`weft_world_copy_triangles`];
//! - state: [`weft_world_snapshot`], [`weft_world_restore`], [`weft_snapshot_destroy`],
//!   [`weft_world_reset`];
//! - errors: every call returns a [`WeftStatus`] (one code per [`WeftError`] kind, plus the
//!   boundary's own: null pointer, bad handle, caught panic) and [`weft_last_error_message`]
//!   says what went wrong.
//!
//! Safety model: every function checks its pointers. A handle is accepted only if it was
//! returned by this library and not yet destroyed (live handles of each type are kept in a
//! registry), so a null, dangling, double-freed or made-up handle gives
//! [`WeftStatus::InvalidHandle`] instead of a crash. Buffers come with their length, which is
//! checked; enumerations come in as `uint32_t` and are checked too (an out-of-range C enum value
//! would be undefined behaviour on the Rust side). A Rust panic never crosses the boundary: it is
//! caught and returned as [`WeftStatus::Panic`]. One handle must not be used from two threads at
//! the same time (different handles may).
//!
//! Ownership: weft owns what its handles point at; the caller frees each handle once with its
//! destroy function. Everything else (parameter structs, arrays, text, output buffers) is the
//! caller's and is only read or written during the call, never kept.

use std::cell::RefCell;
use std::collections::HashSet;
use std::ffi::{c_char, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Mutex;

use crate::model::shapes::Shape;
use crate::obstacles::mesh::TriMesh;
use crate::obstacles::{BroadphaseKind, Obstacle};
use crate::scene::Scene;
use crate::self_collision::{Response, SelfBroadphase, SelfCollision};
use crate::{ClothDesc, Effects, Fabric, PinSpec, Snapshot, SolverParams, WeftError, World};

/// Longest scene text [`weft_world_create_from_scene`] accepts, bytes (16 MiB).
pub const WEFT_MAX_SCENE_BYTES: usize = 16 << 20;

/// Result of every C call.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WeftStatus {
    /// Success.
    Ok = 0,
    /// A required pointer was null.
    NullPointer = 1,
    /// The handle is null, unknown or already destroyed.
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
    /// A triangle mesh cannot be used (message says why).
    InvalidMesh = 9,
    /// Scene text could not be parsed or built (message gives line and column).
    Scene = 10,
    /// File input or output failed (for example a mesh file named by a scene).
    Io = 11,
}

impl WeftStatus {
    /// The status code a [`WeftError`] becomes at the C boundary (one per kind).
    pub fn of(e: &WeftError) -> WeftStatus {
        match e {
            WeftError::InvalidParameter { .. } => WeftStatus::InvalidArgument,
            WeftError::InvalidMesh { .. } => WeftStatus::InvalidMesh,
            WeftError::Diverged { .. } => WeftStatus::Diverged,
            WeftError::BufferLength { .. } => WeftStatus::BufferLength,
            WeftError::IndexOutOfRange { .. } => WeftStatus::IndexOutOfRange,
            WeftError::Scene(_) => WeftStatus::Scene,
            WeftError::Io { .. } => WeftStatus::Io,
        }
    }
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

/// Broadphase of a mesh obstacle (the `broadphase` argument of [`weft_world_add_mesh`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WeftMeshBroadphase {
    /// Uniform grid sized from the faces.
    Grid = 0,
    /// AABB tree of the faces.
    Bvh = 1,
    /// Spatial hash of the faces.
    Hash = 2,
}

/// Self-collision response (the `response` field of [`WeftSelfCollision`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WeftResponse {
    /// Position projection of the collision constraints.
    Pbd = 0,
    /// Velocity based: zero the approaching normal velocity.
    MovementSpeed = 1,
    /// Projection, then the VcCPBD velocity correction (the default).
    Vccpbd = 2,
}

/// Self-collision broadphase (the `broadphase` field of [`WeftSelfCollision`]); both give the
/// same pairs.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WeftSelfBroadphase {
    /// Spatial hash rebuilt each step (the default).
    Hash = 0,
    /// AABB tree built once, refitted each step.
    AabbTree = 1,
}

/// Self-collision settings for [`weft_world_set_self_collision`]; get defaults from
/// [`weft_self_collision_default`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct WeftSelfCollision {
    /// A [`WeftResponse`] value.
    pub response: u32,
    /// A [`WeftSelfBroadphase`] value.
    pub broadphase: u32,
    /// Collision distance, m (> 0), or 0 for the smallest `min(thickness, spacing)` of the
    /// cloths.
    pub distance: f32,
    /// Friction in `[0, 1]`.
    pub friction: f32,
    /// Measure the percentage of particles in penetration after every step (costs time).
    pub measure: bool,
}

/// Per-obstacle options for the `weft_world_add_*` obstacle functions (null = static, with the
/// world's friction).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct WeftObstacleOptions {
    /// Constant velocity, m/s (the obstacle moves from time 0).
    pub velocity: [f32; 3],
    /// Use `friction` instead of the world's coefficient ([`weft_world_set_friction`]).
    pub has_friction: bool,
    /// Own Coulomb friction coefficient (>= 0), if `has_friction`.
    pub friction: f32,
}

/// What one [`weft_world_advance`] call did.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct WeftAdvanceReport {
    /// Fixed steps taken.
    pub steps: u32,
    /// Whether the cap on steps per call was reached.
    pub capped: bool,
    /// Simulated time dropped because of the cap, s.
    pub dropped_time: f64,
    /// Leftover time as a fraction of a step, in `[0, 1)`: the blend factor for
    /// [`weft_world_copy_interpolated_positions`].
    pub alpha: f32,
}

/// An opaque simulated world.
pub struct WeftWorld {
    world: World,
}

/// An opaque copy of a world's evolving state (from [`weft_world_snapshot`]).
pub struct WeftSnapshot {
    snapshot: Snapshot,
}

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

type Registry = Mutex<Option<HashSet<usize>>>;

/// Live world handles.
static WORLDS: Registry = Mutex::new(None);
/// Live snapshot handles.
static SNAPSHOTS: Registry = Mutex::new(None);

fn live<R>(reg: &Registry, f: impl FnOnce(&mut HashSet<usize>) -> R) -> R {
    let mut g = reg.lock().unwrap_or_else(|p| p.into_inner());
    f(g.get_or_insert_with(HashSet::new))
}

fn set_error(msg: &str) {
    let c = CString::new(msg.replace('\0', " ")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = c);
}

type Fail = (WeftStatus, String);

fn fail(s: WeftStatus, msg: impl Into<String>) -> Fail {
    (s, msg.into())
}

impl From<WeftError> for Fail {
    fn from(e: WeftError) -> Fail {
        (WeftStatus::of(&e), e.to_string())
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

fn bad_handle(what: &str) -> Fail {
    fail(
        WeftStatus::InvalidHandle,
        format!("invalid {what} handle (null, unknown or destroyed)"),
    )
}

fn world_mut<'a>(h: *mut WeftWorld) -> Result<&'a mut World, Fail> {
    if h.is_null() || !live(&WORLDS, |s| s.contains(&(h as usize))) {
        return Err(bad_handle("world"));
    }
    // SAFETY: the address is in the registry, so it came from `Box::into_raw` in
    // `register_world` and has not been freed; callers must not share one handle across
    // threads concurrently (documented).
    Ok(unsafe { &mut (*h).world })
}

fn snapshot_ref<'a>(h: *const WeftSnapshot) -> Result<&'a Snapshot, Fail> {
    if h.is_null() || !live(&SNAPSHOTS, |s| s.contains(&(h as usize))) {
        return Err(bad_handle("snapshot"));
    }
    // SAFETY: in the registry, so from `Box::into_raw` in `weft_world_snapshot` and not freed;
    // only read here.
    Ok(unsafe { &(*h).snapshot })
}

fn non_null<T>(p: *const T, name: &str) -> Result<(), Fail> {
    if p.is_null() {
        Err(fail(WeftStatus::NullPointer, format!("`{name}` is null")))
    } else {
        Ok(())
    }
}

/// Checks that `len` elements of `T` can be a slice (`from_raw_parts` needs the byte size to
/// fit `isize`).
fn slice_len<T>(len: usize, name: &str) -> Result<(), Fail> {
    if len.checked_mul(std::mem::size_of::<T>()).is_some_and(|b| b <= isize::MAX as usize) {
        Ok(())
    } else {
        Err(fail(WeftStatus::InvalidArgument, format!("`{name}` length {len} is too large")))
    }
}

/// Borrows `len` readable elements at `p` (checked non-null and of a valid size).
///
/// # Safety
/// If non-null, `p` must point at `len` readable, initialised, aligned elements that stay
/// unchanged during the call.
unsafe fn input<'a, T>(p: *const T, len: usize, name: &str) -> Result<&'a [T], Fail> {
    non_null(p, name)?;
    slice_len::<T>(len, name)?;
    // SAFETY: non-null, size checked; readable by the caller's contract.
    Ok(unsafe { std::slice::from_raw_parts(p, len) })
}

/// Borrows `len` writable elements at `p` (checked non-null and of a valid size).
///
/// # Safety
/// If non-null, `p` must point at `len` writable, aligned elements not otherwise in use during
/// the call.
unsafe fn output<'a, T>(p: *mut T, len: usize, name: &str) -> Result<&'a mut [T], Fail> {
    non_null(p, name)?;
    slice_len::<T>(len, name)?;
    // SAFETY: non-null, size checked; writable and unaliased by the caller's contract.
    Ok(unsafe { std::slice::from_raw_parts_mut(p, len) })
}

/// Reads three floats at `p`.
///
/// # Safety
/// If non-null, `p` must point at 3 readable floats.
unsafe fn vec3(p: *const f32, name: &str) -> Result<[f32; 3], Fail> {
    // SAFETY: forwarded contract.
    let s = unsafe { input(p, 3, name) }?;
    Ok([s[0], s[1], s[2]])
}

/// Writes `v` to `*p` if `p` is non-null.
///
/// # Safety
/// If non-null, `p` must point at a writable `T`.
unsafe fn put_opt<T>(p: *mut T, v: T) {
    if !p.is_null() {
        // SAFETY: non-null and writable by the caller's contract.
        unsafe { p.write(v) };
    }
}

/// Writes `v` to `*p`, which must not be null.
///
/// # Safety
/// If non-null, `p` must point at a writable `T`.
unsafe fn put<T>(p: *mut T, v: T, name: &str) -> Result<(), Fail> {
    non_null(p, name)?;
    // SAFETY: non-null and writable by the caller's contract.
    unsafe { p.write(v) };
    Ok(())
}

/// Boxes a world, registers the handle and writes it to `out` (checked non-null by the caller).
///
/// # Safety
/// `out` must be non-null and writable.
unsafe fn register_world(world: World, out: *mut *mut WeftWorld) {
    let h = Box::into_raw(Box::new(WeftWorld { world }));
    live(&WORLDS, |s| s.insert(h as usize));
    // SAFETY: non-null (checked by every caller) and writable by the contract.
    unsafe { out.write(h) };
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

/// Adds an obstacle built by `make`, with the options at `options` (may be null), and writes
/// its index to `out_index` (may be null).
///
/// # Safety
/// `options`, if non-null, must point at a readable [`WeftObstacleOptions`]; `out_index`, if
/// non-null, at a writable `uint32_t`.
unsafe fn add_obstacle(
    world: *mut WeftWorld,
    options: *const WeftObstacleOptions,
    out_index: *mut u32,
    make: impl FnOnce() -> Result<Obstacle, Fail>,
) -> WeftStatus {
    boundary(|| {
        let w = world_mut(world)?;
        let mut o = make()?;
        if !options.is_null() {
            // SAFETY: non-null and readable by the contract.
            let opt = unsafe { *options };
            o = o.with_velocity(opt.velocity)?;
            if opt.has_friction {
                o = o.with_friction(opt.friction)?;
            }
        }
        let k = w.add_obstacle(o)?;
        // SAFETY: writable if non-null by the contract.
        unsafe { put_opt(out_index, k as u32) };
        Ok(())
    })
}

/// Adds a solid half-space: the plane through `point` (3 floats) with outward normal `normal`
/// (3 floats, normalised here, must not be zero). `options` may be null; `out_index` (may be
/// null) receives the obstacle index.
///
/// # Safety
/// `point` and `normal` must point at 3 readable floats; `options` and `out_index` as in
/// [`weft_world_add_sphere`].
#[no_mangle]
pub unsafe extern "C" fn weft_world_add_plane(
    world: *mut WeftWorld,
    point: *const f32,
    normal: *const f32,
    options: *const WeftObstacleOptions,
    out_index: *mut u32,
) -> WeftStatus {
    // SAFETY: forwarded contract.
    unsafe {
        add_obstacle(world, options, out_index, || {
            let s = Shape::plane(vec3(point, "point")?, vec3(normal, "normal")?)?;
            Ok(Obstacle::shape(s)?)
        })
    }
}

/// Adds a solid ball at `center` (3 floats) of `radius` m (> 0). `options` may be null (static,
/// world friction); `out_index` (may be null) receives the obstacle index.
///
/// # Safety
/// `center` must point at 3 readable floats; `options`, if non-null, at a readable
/// [`WeftObstacleOptions`]; `out_index`, if non-null, at a writable `uint32_t`.
#[no_mangle]
pub unsafe extern "C" fn weft_world_add_sphere(
    world: *mut WeftWorld,
    center: *const f32,
    radius: f32,
    options: *const WeftObstacleOptions,
    out_index: *mut u32,
) -> WeftStatus {
    // SAFETY: forwarded contract.
    unsafe {
        add_obstacle(world, options, out_index, || {
            let center = vec3(center, "center")?;
            Ok(Obstacle::shape(Shape::Sphere { center, radius })?)
        })
    }
}

/// Adds a capsule: all points within `radius` m (> 0) of the segment from `a` to `b` (3 floats
/// each). `options` and `out_index` as in [`weft_world_add_sphere`].
///
/// # Safety
/// `a` and `b` must point at 3 readable floats; `options` and `out_index` as in
/// [`weft_world_add_sphere`].
#[no_mangle]
pub unsafe extern "C" fn weft_world_add_capsule(
    world: *mut WeftWorld,
    a: *const f32,
    b: *const f32,
    radius: f32,
    options: *const WeftObstacleOptions,
    out_index: *mut u32,
) -> WeftStatus {
    // SAFETY: forwarded contract.
    unsafe {
        add_obstacle(world, options, out_index, || {
            let (a, b) = (vec3(a, "a")?, vec3(b, "b")?);
            Ok(Obstacle::shape(Shape::Capsule { a, b, radius })?)
        })
    }
}

/// Adds a solid box at `center` with half extents `half` (3 floats each, > 0), rotated by
/// `rotation_deg` degrees about x, then y, then z (3 floats; null = axis aligned). `options`
/// and `out_index` as in [`weft_world_add_sphere`].
///
/// # Safety
/// `center` and `half` must point at 3 readable floats, `rotation_deg` too if non-null;
/// `options` and `out_index` as in [`weft_world_add_sphere`].
#[no_mangle]
pub unsafe extern "C" fn weft_world_add_box(
    world: *mut WeftWorld,
    center: *const f32,
    half: *const f32,
    rotation_deg: *const f32,
    options: *const WeftObstacleOptions,
    out_index: *mut u32,
) -> WeftStatus {
    // SAFETY: forwarded contract.
    unsafe {
        add_obstacle(world, options, out_index, || {
            let (center, half) = (vec3(center, "center")?, vec3(half, "half")?);
            let deg = if rotation_deg.is_null() {
                [0.0; 3]
            } else {
                crate::error::finite3("box.rotation", vec3(rotation_deg, "rotation_deg")?)?
            };
            let axes = Shape::axes_from_euler_deg(deg);
            Ok(Obstacle::shape(Shape::Box { center, half, axes })?)
        })
    }
}

/// Adds a triangle-mesh obstacle: `vertex_floats` floats at `vertices` (`x0 y0 z0 x1 ...`, a
/// multiple of 3) and `index_count` vertex indices at `indices` (three per triangle, a multiple
/// of 3). `broadphase` is a [`WeftMeshBroadphase`] value; `face_memory` turns on the per-particle
/// face memory. Zero-area faces are dropped; a mesh with none left, a non-finite vertex or an
/// index out of range gives [`WeftStatus::InvalidMesh`]. The arrays are copied.
/// `options` and `out_index` as in [`weft_world_add_sphere`].
///
/// # Safety
/// `vertices` must point at `vertex_floats` readable floats, `indices` at `index_count`
/// readable `uint32_t`; `options` and `out_index` as in [`weft_world_add_sphere`].
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn weft_world_add_mesh(
    world: *mut WeftWorld,
    vertices: *const f32,
    vertex_floats: usize,
    indices: *const u32,
    index_count: usize,
    broadphase: u32,
    face_memory: bool,
    options: *const WeftObstacleOptions,
    out_index: *mut u32,
) -> WeftStatus {
    // SAFETY: forwarded contract.
    unsafe {
        add_obstacle(world, options, out_index, || {
            let v = input(vertices, vertex_floats, "vertices")?;
            let f = input(indices, index_count, "indices")?;
            for (len, name) in [(vertex_floats, "vertices"), (index_count, "indices")] {
                if len % 3 != 0 {
                    return Err(fail(
                        WeftStatus::BufferLength,
                        format!("`{name}` length {len} is not a multiple of 3"),
                    ));
                }
            }
            let kind = match broadphase {
                0 => BroadphaseKind::Grid(None),
                1 => BroadphaseKind::Bvh,
                2 => BroadphaseKind::Hash,
                k => {
                    return Err(fail(
                        WeftStatus::InvalidArgument,
                        format!("mesh broadphase {k} is not 0 (grid), 1 (bvh) or 2 (hash)"),
                    ))
                }
            };
            let verts = v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
            let faces = f.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
            let (mesh, _report) = TriMesh::new(verts, faces)?;
            Ok(Obstacle::mesh(mesh, kind, face_memory)?)
        })
    }
}

/// Sets the Coulomb friction coefficient (>= 0) of obstacles that have none of their own.
///
/// # Safety
/// `world` must not be used concurrently from another thread.
#[no_mangle]
pub unsafe extern "C" fn weft_world_set_friction(world: *mut WeftWorld, mu: f32) -> WeftStatus {
    boundary(|| Ok(world_mut(world)?.set_friction(mu)?))
}

/// The default self-collision settings (VcCPBD response, hash broadphase, automatic distance,
/// friction 0.3, no measuring).
#[no_mangle]
pub extern "C" fn weft_self_collision_default() -> WeftSelfCollision {
    let d = SelfCollision::default();
    WeftSelfCollision {
        response: match d.response {
            Response::Pbd => WeftResponse::Pbd,
            Response::MovementSpeed => WeftResponse::MovementSpeed,
            Response::Vccpbd => WeftResponse::Vccpbd,
        } as u32,
        broadphase: match d.broadphase {
            SelfBroadphase::Hash => WeftSelfBroadphase::Hash,
            SelfBroadphase::AabbTree => WeftSelfBroadphase::AabbTree,
        } as u32,
        distance: d.distance.unwrap_or(0.0),
        friction: d.friction,
        measure: d.measure,
    }
}

/// Turns self-collision on with the settings at `config`, or off if `config` is null.
/// Invalid settings change nothing.
///
/// # Safety
/// `config`, if non-null, must point at a readable [`WeftSelfCollision`].
#[no_mangle]
pub unsafe extern "C" fn weft_world_set_self_collision(world: *mut WeftWorld, config: *const WeftSelfCollision) -> WeftStatus {
    boundary(|| {
        let w = world_mut(world)?;
        if config.is_null() {
            return Ok(w.set_self_collision(None)?);
        }
        // SAFETY: non-null and readable by the contract.
        let c = unsafe { *config };
        let response = match c.response {
            0 => Response::Pbd,
            1 => Response::MovementSpeed,
            2 => Response::Vccpbd,
            k => return Err(WeftError::param("self_collision.response", k, "must be 0 (pbd), 1 (movement-speed) or 2 (vccpbd)").into()),
        };
        let broadphase = match c.broadphase {
            0 => SelfBroadphase::Hash,
            1 => SelfBroadphase::AabbTree,
            k => return Err(WeftError::param("self_collision.broadphase", k, "must be 0 (hash) or 1 (aabb-tree)").into()),
        };
        let sc = SelfCollision {
            distance: (c.distance != 0.0).then_some(c.distance),
            friction: c.friction,
            response,
            broadphase,
            measure: c.measure,
        };
        Ok(w.set_self_collision(Some(sc))?)
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

/// Writes the number of particles to `*out`.
///
/// # Safety
/// `out` must point at a writable `size_t`.
#[no_mangle]
pub unsafe extern "C" fn weft_world_particle_count(world: *mut WeftWorld, out: *mut usize) -> WeftStatus {
    boundary(|| {
        let w = world_mut(world)?;
        // SAFETY: writable by the contract.
        unsafe { put(out, w.particle_count(), "out") }
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
        // SAFETY: `len` writable floats by the contract.
        let buf = unsafe { output(out, len, "out") }?;
        Ok(w.read_positions(buf)?)
    })
}

/// Copies positions for display between the last two steps taken by [`weft_world_advance`],
/// `x_prev + alpha (x - x_prev)` with `alpha` in `[0, 1]` (usually
/// [`WeftAdvanceReport::alpha`]), interleaved into `out` (`len` = 3 times the particle count).
/// If the last step was not taken by `weft_world_advance`, the current positions are written.
///
/// # Safety
/// `out` must point at `len` writable floats.
#[no_mangle]
pub unsafe extern "C" fn weft_world_copy_interpolated_positions(
    world: *mut WeftWorld,
    alpha: f32,
    out: *mut f32,
    len: usize,
) -> WeftStatus {
    boundary(|| {
        let w = world_mut(world)?;
        // SAFETY: `len` writable floats by the contract.
        let buf = unsafe { output(out, len, "out") }?;
        Ok(w.interpolated_positions(alpha, buf)?)
    })
}

/// Copies area-weighted unit vertex normals, interleaved, into `out` (`len` = 3 times the
/// particle count); a particle in no triangle gets the zero vector.
///
/// # Safety
/// `out` must point at `len` writable floats.
#[no_mangle]
pub unsafe extern "C" fn weft_world_copy_normals(world: *mut WeftWorld, out: *mut f32, len: usize) -> WeftStatus {
    boundary(|| {
        let w = world_mut(world)?;
        // SAFETY: `len` writable floats by the contract.
        let buf = unsafe { output(out, len, "out") }?;
        Ok(w.read_normals(buf)?)
    })
}

/// Writes the number of render triangles (all cloths) to `*out`.
///
/// # Safety
/// `out` must point at a writable `size_t`.
#[no_mangle]
pub unsafe extern "C" fn weft_world_triangle_count(world: *mut WeftWorld, out: *mut usize) -> WeftStatus {
    boundary(|| {
        let w = world_mut(world)?;
        // SAFETY: writable by the contract.
        unsafe { put(out, w.triangles().len(), "out") }
    })
}

/// Copies the render triangles as particle indices, `a0 b0 c0 a1 ...`, into `out` (`len` =
/// 3 times the triangle count). They wind counter-clockwise about the normals of
/// [`weft_world_copy_normals`].
///
/// # Safety
/// `out` must point at `len` writable `uint32_t`.
#[no_mangle]
pub unsafe extern "C" fn weft_world_copy_triangles(world: *mut WeftWorld, out: *mut u32, len: usize) -> WeftStatus {
    boundary(|| {
        let w = world_mut(world)?;
        // SAFETY: `len` writable `uint32_t` by the contract.
        let buf = unsafe { output(out, len, "out") }?;
        let t = w.triangles();
        if len != t.len().saturating_mul(3) {
            return Err(WeftError::BufferLength {
                name: "triangles",
                got: len,
                expected: t.len().saturating_mul(3),
            }
            .into());
        }
        for (dst, src) in buf.chunks_exact_mut(3).zip(t) {
            dst.copy_from_slice(src);
        }
        Ok(())
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
