//! The raw views the wave hands ranges of particles out through ([`RawParticles`],
//! [`RawSaved`]): tasks that sweep constraints elsewhere meanwhile take disjoint ranges.

use super::{ParticleChunk, Particles};
use crate::data::lanes::SharedVec3;

/// The particle arrays as raw pointers, for a pass whose tasks sweep constraints through a
/// [`SharedVec3`] view of the predictions and finish ranges of particles whose constraints
/// are done ([`chunk`](Self::chunk)) while other tasks still sweep elsewhere.
///
/// The view holds the particles' mutable borrow for `'a`, so nothing else touches them while
/// it lives.
#[derive(Clone, Copy, Debug)]
pub struct RawParticles<'a> {
    /// `x, y, z, px, py, pz, vx, vy, vz`.
    arrays: [*mut f32; 9],
    w: *const f32,
    len: usize,
    _borrow: std::marker::PhantomData<&'a mut Particles>,
}

// SAFETY: pointers and a length; the methods that hand out mutable access are `unsafe`, and
// their callers guarantee that tasks touch disjoint particles.
unsafe impl Send for RawParticles<'_> {}
// SAFETY: as above.
unsafe impl Sync for RawParticles<'_> {}

impl<'a> RawParticles<'a> {
    /// Captures the arrays of `p` (padded length) for `'a`.
    pub fn new(p: &'a mut Particles) -> Self {
        let len = p.padded_len();
        let arrays = [
            &mut p.x, &mut p.y, &mut p.z, &mut p.px, &mut p.py, &mut p.pz, &mut p.vx, &mut p.vy, &mut p.vz,
        ]
        .map(|a| {
            assert_eq!(a.len(), len);
            a.as_mut_ptr()
        });
        assert_eq!(p.w.len(), len);
        RawParticles {
            arrays,
            w: p.w.as_ptr(),
            len,
            _borrow: std::marker::PhantomData,
        }
    }

    /// Padded number of particles.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The predictions, for the constraint sweep (whose accesses are `unsafe`, under
    /// `SharedVec3`'s rules; the view must outlive them).
    pub fn p(&self) -> SharedVec3 {
        // SAFETY: the three arrays are valid for `len` elements for `'a`.
        unsafe { SharedVec3::from_raw(self.arrays[3], self.arrays[4], self.arrays[5], self.len) }
    }

    /// The inverse masses.
    pub fn w(&self) -> &'a [f32] {
        // SAFETY: the view borrows the particles for `'a` and never writes the inverse masses.
        unsafe { std::slice::from_raw_parts(self.w, self.len) }
    }

    /// Particles `range` as a chunk.
    ///
    /// # Safety
    /// `range` is in bounds, and no other task reads or writes these particles (through
    /// another chunk or the sweep's view) while the chunk lives.
    pub unsafe fn chunk(&self, range: std::ops::Range<usize>) -> ParticleChunk<'a> {
        assert!(range.start <= range.end && range.end <= self.len);
        let n = range.end - range.start;
        // SAFETY: in bounds (checked above) and exclusive by the caller's guarantee.
        let a = |k: usize| unsafe { std::slice::from_raw_parts_mut(self.arrays[k].add(range.start), n) };
        // SAFETY: in bounds; only read.
        let w = unsafe { std::slice::from_raw_parts(self.w.add(range.start), n) };
        ParticleChunk::from_arrays(range.start, std::array::from_fn(a), w)
    }
}

/// A raw view of six saved arrays (see [`Particles::for_chunks_saving`]) that tasks fill by
/// disjoint ranges, beside a [`RawParticles`] view.
pub struct RawSaved<'a> {
    arrays: [*mut f32; 6],
    len: usize,
    _borrow: std::marker::PhantomData<&'a mut [f32]>,
}

// SAFETY: pointers and a length; `range` is `unsafe`, and its callers hand each range to one
// task.
unsafe impl Send for RawSaved<'_> {}
// SAFETY: as above.
unsafe impl Sync for RawSaved<'_> {}

impl<'a> RawSaved<'a> {
    /// Resizes `saved` to `len` values each (allocating only when not yet sized) and captures
    /// the arrays for `'a`.
    pub fn new(saved: &'a mut [Vec<f32>; 6], len: usize) -> Self {
        let arrays = saved.each_mut().map(|s| {
            s.resize(len, 0.0);
            s.as_mut_ptr()
        });
        RawSaved {
            arrays,
            len,
            _borrow: std::marker::PhantomData,
        }
    }

    /// Values `range` of the six arrays.
    ///
    /// # Safety
    /// No other task reads or writes `range` of these arrays while the slices live.
    pub unsafe fn range(&self, range: std::ops::Range<usize>) -> [&'a mut [f32]; 6] {
        assert!(range.start <= range.end && range.end <= self.len);
        // SAFETY: in bounds (checked above) and exclusive by the caller's guarantee.
        self.arrays
            .map(|a| unsafe { std::slice::from_raw_parts_mut(a.add(range.start), range.end - range.start) })
    }
}
