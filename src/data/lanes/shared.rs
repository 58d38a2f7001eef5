//! [`SharedVec3`]: the raw view parallel tasks write disjoint particles through.

use super::{F32s, Idx8, Vec3x8, LANES};

/// A raw view of three particle arrays (`x`, `y`, `z`) that parallel tasks may gather from and
/// scatter into at indices that no other task touches at the same time.
///
/// Constraint colouring guarantees that within one colour no particle appears twice, so the
/// tasks solving one colour write disjoint elements. That guarantee is what makes the `unsafe`
/// below sound; every caller states it.
#[derive(Clone, Copy)]
pub struct SharedVec3 {
    x: *mut f32,
    y: *mut f32,
    z: *mut f32,
    len: usize,
}

// SAFETY: `SharedVec3` is only a pointer triple; the methods that dereference it are `unsafe`
// and their callers guarantee disjoint access (see the type docs).
unsafe impl Send for SharedVec3 {}
// SAFETY: as above.
unsafe impl Sync for SharedVec3 {}

impl SharedVec3 {
    /// Captures the three arrays, which must have equal length.
    pub fn new(x: &mut [f32], y: &mut [f32], z: &mut [f32]) -> Self {
        assert!(x.len() == y.len() && y.len() == z.len());
        Self {
            x: x.as_mut_ptr(),
            y: y.as_mut_ptr(),
            z: z.as_mut_ptr(),
            len: x.len(),
        }
    }

    /// A view of three arrays given by their pointers.
    ///
    /// # Safety
    /// Each pointer is valid for reads and writes of `len` elements for as long as the view
    /// is used, and the arrays are accessed only as the type docs allow meanwhile.
    pub unsafe fn from_raw(x: *mut f32, y: *mut f32, z: *mut f32, len: usize) -> Self {
        Self { x, y, z, len }
    }

    /// Number of elements in each array.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the arrays are empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Gathers eight 3-vectors.
    ///
    /// # Safety
    /// Every index must be `< len`, and no other thread may be writing these elements.
    #[inline(always)]
    pub unsafe fn gather(&self, idx: &Idx8) -> Vec3x8 {
        let mut x = [0.0f32; LANES];
        let mut y = [0.0f32; LANES];
        let mut z = [0.0f32; LANES];
        for l in 0..LANES {
            let i = idx[l] as usize;
            debug_assert!(i < self.len);
            // SAFETY: the caller guarantees `i < len` and no concurrent writer.
            unsafe {
                x[l] = *self.x.add(i);
                y[l] = *self.y.add(i);
                z[l] = *self.z.add(i);
            }
        }
        Vec3x8 {
            x: F32s::from(x),
            y: F32s::from(y),
            z: F32s::from(z),
        }
    }

    /// Scatters eight 3-vectors, lane 0 first. When an index repeats, the later lane wins.
    ///
    /// # Safety
    /// Every index must be `< len`, and no other thread may read or write these elements.
    #[inline(always)]
    pub unsafe fn scatter(&self, idx: &Idx8, v: Vec3x8) {
        let x = v.x.to_array();
        let y = v.y.to_array();
        let z = v.z.to_array();
        for l in 0..LANES {
            let i = idx[l] as usize;
            debug_assert!(i < self.len);
            // SAFETY: the caller guarantees `i < len` and exclusive access.
            unsafe {
                *self.x.add(i) = x[l];
                *self.y.add(i) = y[l];
                *self.z.add(i) = z[l];
            }
        }
    }

    /// Loads the eight consecutive 3-vectors at `i..i + 8` (contiguous loads, no gather).
    ///
    /// # Safety
    /// `i + 8 <= len`, and no other thread may be writing these elements.
    #[inline(always)]
    pub unsafe fn load_run(&self, i: usize) -> Vec3x8 {
        debug_assert!(i + LANES <= self.len);
        // SAFETY: the caller guarantees the range is in bounds and not concurrently written.
        unsafe {
            Vec3x8 {
                x: F32s::from(self.x.add(i).cast::<[f32; LANES]>().read_unaligned()),
                y: F32s::from(self.y.add(i).cast::<[f32; LANES]>().read_unaligned()),
                z: F32s::from(self.z.add(i).cast::<[f32; LANES]>().read_unaligned()),
            }
        }
    }

    /// Stores eight 3-vectors at `i..i + 8` (contiguous stores, no scatter).
    ///
    /// # Safety
    /// `i + 8 <= len`, and no other thread may read or write these elements.
    #[inline(always)]
    pub unsafe fn store_run(&self, i: usize, v: Vec3x8) {
        debug_assert!(i + LANES <= self.len);
        // SAFETY: the caller guarantees the range is in bounds and exclusively owned.
        unsafe {
            self.x.add(i).cast::<[f32; LANES]>().write_unaligned(v.x.to_array());
            self.y.add(i).cast::<[f32; LANES]>().write_unaligned(v.y.to_array());
            self.z.add(i).cast::<[f32; LANES]>().write_unaligned(v.z.to_array());
        }
    }

    /// Reads one 3-vector.
    ///
    /// # Safety
    /// `i < len`, and no other thread may be writing element `i`.
    #[inline(always)]
    pub unsafe fn get(&self, i: usize) -> [f32; 3] {
        debug_assert!(i < self.len);
        // SAFETY: guaranteed by the caller.
        unsafe { [*self.x.add(i), *self.y.add(i), *self.z.add(i)] }
    }

    /// Writes one 3-vector.
    ///
    /// # Safety
    /// `i < len`, and no other thread may read or write element `i`.
    #[inline(always)]
    pub unsafe fn set(&self, i: usize, v: [f32; 3]) {
        debug_assert!(i < self.len);
        // SAFETY: guaranteed by the caller.
        unsafe {
            *self.x.add(i) = v[0];
            *self.y.add(i) = v[1];
            *self.z.add(i) = v[2];
        }
    }
}
