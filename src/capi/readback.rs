//! Reading positions, normals and triangles into the caller's buffers.

use super::*;

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
