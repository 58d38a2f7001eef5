//! Obstacles (the analytic shapes and triangle meshes) and self-collision settings.

use super::*;

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
/// friction 0.3, no measuring, travel 1).
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
        travel: d.travel,
    }
}

/// Writes to `*out` the number of steps that ran without self-collision because their pair
/// lists could not be built (more than `MAX_PAIRS_PER_PARTICLE`, 128, pairs a particle on
/// average: a cloth collapsed onto itself or a distance far above the spacing). 0 while it
/// holds; [`weft_last_error_message`] does not carry the reason, the step itself succeeded.
///
/// # Safety
/// `out` must point at a writable `uint64_t`.
#[no_mangle]
pub unsafe extern "C" fn weft_world_self_collision_failed_steps(world: *mut WeftWorld, out: *mut u64) -> WeftStatus {
    boundary(|| {
        let w = world_mut(world)?;
        // SAFETY: writable by the contract.
        unsafe { put(out, w.self_collision_stats().failed_steps, "out") }
    })
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
            travel: c.travel,
        };
        Ok(w.set_self_collision(Some(sc))?)
    })
}
