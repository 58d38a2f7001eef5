//! C interface (cargo feature `capi`): opaque world and snapshot handles, status codes and a
//! thread-local last-error message. The header `include/weft.h` is generated from these files by
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

use std::ffi::{c_char, CStr, CString};
use std::sync::Mutex;

use crate::model::shapes::Shape;
use crate::obstacles::mesh::TriMesh;
use crate::obstacles::{BroadphaseKind, Obstacle};
use crate::scene::Scene;
use crate::self_collision::{Response, SelfBroadphase, SelfCollision};
use crate::{ClothDesc, Effects, Fabric, PinSpec, Snapshot, SolverParams, WeftError, World};

/// Longest scene text [`weft_world_create_from_scene`] accepts, bytes (4 MiB: the limit of a
/// scene file, `files::SCENE_LIMIT`, for the same format).
pub const WEFT_MAX_SCENE_BYTES: usize = 4 << 20;

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
    /// Worker threads: 0 = all cores (global pool) or the calling thread, whichever the world
    /// measures faster; 1 = the calling thread; k = own pool of k threads.
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
    /// The travel bound over the collision distance, above 0 and at most 2 (default 1): how
    /// far a particle may move in a step relative to the mean motion at most (each particle uses
    /// what its velocity calls for, up to it). Lower is cheaper and clamps harder.
    pub travel: f32,
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

/// Where a `threads = 0` world's steps run ([`weft_world_thread_choice`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct WeftThreadChoice {
    /// Whether a trial has chosen (false for other thread settings and before the first
    /// trial ends; the other fields are then zero).
    pub chosen: bool,
    /// The steps run on the calling thread (else in the global pool).
    pub caller_thread: bool,
    /// Shortest trial step in the pool, ms.
    pub pool_ms: f64,
    /// Shortest trial step on the calling thread, ms.
    pub caller_ms: f64,
}

/// An opaque simulated world.
pub struct WeftWorld {
    world: World,
}

/// An opaque copy of a world's evolving state (from [`weft_world_snapshot`]).
pub struct WeftSnapshot {
    snapshot: Snapshot,
}

mod boundary;
mod obstacles;
mod readback;
mod world;

use boundary::*;
pub use obstacles::*;
pub use readback::*;
pub use world::*;
