//! The lane vocabulary: the only module that knows the SIMD width.
//!
//! Kernels are written over [`Vec3x8`] (eight 3-vectors in three `f32x8` registers) and read
//! like the math. Particle arrays are padded to a multiple of [`LANES`] so that hot loops have
//! no scalar tail. The unchecked loads, gathers and scatters, and the shared write handle
//! [`SharedVec3`], are defined here with their safety contracts; their callers (the
//! constraint, spring and self-collision kernels) check the indices once before using them.
//!
//! The vocabulary in four parts: lane loads and stores and [`Vec3x8`] (here), indexed loads
//! and gathers (`gather`), the permutations of a sixteen-particle window (`window`), and the
//! shared write handle (`shared`); all are re-exported here.
//!
//! A kernel never fuses `a * b + c` implicitly: it rounds twice in both the SIMD kernels and
//! their scalar twins. Where a kernel fuses, it says so with [`mul_add`] in its lanes and
//! `f32::mul_add` in its twin: one rounding on every target (the FMA instruction where the build
//! enables it, else a correctly rounded fallback), so the two still agree bit for bit whatever
//! target features the build enables, and a build without FMA is slower, not different.

mod gather;
mod shared;
mod window;

pub use gather::*;
pub use shared::SharedVec3;
pub use window::*;

use wide::f32x8;

/// Number of `f32` lanes a kernel processes at once.
pub const LANES: usize = 8;

/// The lane type.
pub type F32s = f32x8;

/// `a * b + c` with one rounding in every lane, on every target: lane for lane the value of
/// `f32::mul_add`. The FMA instruction when the build enables it; otherwise `f32::mul_add` lane
/// by lane (correctly rounded, slower), never the twice-rounded product and sum.
#[inline(always)]
pub fn mul_add(a: F32s, b: F32s, c: F32s) -> F32s {
    #[cfg(all(any(target_arch = "x86", target_arch = "x86_64"), target_feature = "avx", target_feature = "fma"))]
    {
        a.mul_add(b, c)
    }
    #[cfg(not(all(any(target_arch = "x86", target_arch = "x86_64"), target_feature = "avx", target_feature = "fma")))]
    {
        let (a, b, c) = (a.to_array(), b.to_array(), c.to_array());
        F32s::from(std::array::from_fn::<f32, LANES, _>(|l| a[l].mul_add(b[l], c[l])))
    }
}

/// Rounds `n` up to a multiple of [`LANES`].
#[inline]
pub const fn round_up(n: usize) -> usize {
    n.div_ceil(LANES) * LANES
}

/// Loads eight consecutive values starting at `i` (which must be a multiple of the lane width
/// for aligned use, though any `i` with `i + 8 <= s.len()` works).
#[inline(always)]
pub fn load(s: &[f32], i: usize) -> F32s {
    let a: [f32; LANES] = s[i..i + LANES].try_into().expect("slice of lane width");
    F32s::from(a)
}

/// [`load`] without the bounds check.
///
/// # Safety
/// `i + LANES <= s.len()`.
#[inline(always)]
pub unsafe fn load_unchecked(s: &[f32], i: usize) -> F32s {
    debug_assert!(i + LANES <= s.len());
    // SAFETY: the caller guarantees the eight values are inside `s`.
    F32s::from(unsafe { std::ptr::read_unaligned(s.as_ptr().add(i).cast::<[f32; LANES]>()) })
}

/// Stores eight values at `i..i + 8`.
#[inline(always)]
pub fn store(s: &mut [f32], i: usize, v: F32s) {
    s[i..i + LANES].copy_from_slice(&v.to_array());
}

/// Stores eight values at `i..i + 8` without a bounds check.
///
/// # Safety
/// `i + LANES <= s.len()`.
#[inline(always)]
pub unsafe fn store_unchecked(s: &mut [f32], i: usize, v: F32s) {
    debug_assert!(i + LANES <= s.len());
    // SAFETY: the caller guarantees the eight values are inside `s`.
    unsafe { std::ptr::write_unaligned(s.as_mut_ptr().add(i).cast::<[f32; LANES]>(), v.to_array()) }
}

/// Eight 3-vectors, one per lane.
#[derive(Clone, Copy, Debug)]
pub struct Vec3x8 {
    /// x components.
    pub x: F32s,
    /// y components.
    pub y: F32s,
    /// z components.
    pub z: F32s,
}

impl Vec3x8 {
    /// The same vector in every lane.
    #[inline(always)]
    pub fn splat(v: [f32; 3]) -> Self {
        Self {
            x: F32s::splat(v[0]),
            y: F32s::splat(v[1]),
            z: F32s::splat(v[2]),
        }
    }
    /// Loads lanes `i..i + 8` of three arrays.
    #[inline(always)]
    pub fn load(x: &[f32], y: &[f32], z: &[f32], i: usize) -> Self {
        Self {
            x: load(x, i),
            y: load(y, i),
            z: load(z, i),
        }
    }
    /// Stores into lanes `i..i + 8` of three arrays.
    #[inline(always)]
    pub fn store(self, x: &mut [f32], y: &mut [f32], z: &mut [f32], i: usize) {
        store(x, i, self.x);
        store(y, i, self.y);
        store(z, i, self.z);
    }
    /// Lane-wise dot product.
    #[inline(always)]
    pub fn dot(self, o: Self) -> F32s {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    /// Lane-wise squared length.
    #[inline(always)]
    pub fn length_sq(self) -> F32s {
        self.dot(self)
    }
    /// Lane-wise scaling by `s`.
    #[inline(always)]
    pub fn scale(self, s: F32s) -> Self {
        Self {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
    /// Per-lane choice: `mask ? a : b`.
    #[inline(always)]
    pub fn select(mask: F32s, a: Self, b: Self) -> Self {
        Self {
            x: mask.select(a.x, b.x),
            y: mask.select(a.y, b.y),
            z: mask.select(a.z, b.z),
        }
    }
}

impl std::ops::Add for Vec3x8 {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl std::ops::Sub for Vec3x8 {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl std::ops::Div<F32s> for Vec3x8 {
    type Output = Self;
    /// Each component divided by its lane of `s`.
    #[inline(always)]
    fn div(self, s: F32s) -> Self {
        Self {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }
}

/// The lanes of `v` that are finite (`|v| < inf` fails exactly for NaN and ±inf), as a mask.
#[inline(always)]
pub fn finite_lanes(v: F32s) -> F32s {
    v.abs().simd_lt(F32s::splat(f32::INFINITY))
}

#[cfg(test)]
mod tests;
