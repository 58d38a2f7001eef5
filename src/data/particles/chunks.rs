//! The chunked passes over [`Particles`]: [`ParticleChunk`], a contiguous range handed to an
//! element-wise kernel, the passes that run a kernel over chunks of [`chunk_len`] particles
//! (serially or on the rayon pool; the same bits either way), the raw views the wave hands
//! ranges out through ([`RawParticles`], [`RawSaved`]), and the guard's finite check of a
//! chunk ([`chunk_finite_simd`] and its scalar twin).

use super::Particles;
use crate::data::lanes::SharedVec3;

/// Particles up to which an element-wise pass runs as one chunk on the calling thread.
pub const CHUNK: usize = 4096;

/// Chunks start on multiples of this many particles (a multiple of the lane width; the mean
/// velocity's partial sums, filled chunk by chunk, cover this many particles each).
pub const CHUNK_ALIGN: usize = 256;

/// The chunk length of the element-wise passes over `len` (padded) particles: above
/// [`CHUNK`], `len` cut into an even number of chunks of at most `2 CHUNK` (multiples of
/// [`CHUNK_ALIGN`]), so that two threads get about the same share (10 000 particles: two
/// chunks of 5 120 and 4 880, where chunks of 4 096 gave one thread 8 192 of them). The cut
/// depends on `len` only, never on the threads, and the element-wise kernels give the same
/// bits whatever it is.
pub fn chunk_len(len: usize) -> usize {
    if len <= CHUNK {
        return len.max(1);
    }
    let k = len.div_ceil(2 * CHUNK).max(2).next_multiple_of(2);
    len.div_ceil(k).next_multiple_of(CHUNK_ALIGN)
}

/// A contiguous range of particles handed to an element-wise kernel.
#[derive(Debug)]
pub struct ParticleChunk<'a> {
    /// Index of the first particle of the chunk.
    pub start: usize,
    /// Positions.
    pub x: &'a mut [f32],
    /// Positions.
    pub y: &'a mut [f32],
    /// Positions.
    pub z: &'a mut [f32],
    /// Predicted positions.
    pub px: &'a mut [f32],
    /// Predicted positions.
    pub py: &'a mut [f32],
    /// Predicted positions.
    pub pz: &'a mut [f32],
    /// Velocities.
    pub vx: &'a mut [f32],
    /// Velocities.
    pub vy: &'a mut [f32],
    /// Velocities.
    pub vz: &'a mut [f32],
    /// Inverse masses.
    pub w: &'a [f32],
}

impl Particles {
    /// Runs `f` over chunks of [`chunk_len`] particles, in parallel on the current rayon pool when
    /// `parallel`, else as one chunk on this thread. Element-wise kernels give the same bits
    /// either way. Two chunks run as one `rayon::join`: on two threads that costs about a
    /// microsecond less a pass than the parallel iterator's splitting (10 000 particles).
    pub fn for_chunks<F>(&mut self, parallel: bool, f: F)
    where
        F: Fn(ParticleChunk<'_>) + Sync + Send,
    {
        use rayon::prelude::*;
        let len = self.padded_len();
        if parallel && len > CHUNK && len <= 2 * chunk_len(len) {
            // Two chunks: one join, without the parallel iterator's splitting.
            let (a, b) = self.whole().split_at(chunk_len(len));
            rayon::join(|| f(a), || f(b));
        } else if parallel && len > CHUNK {
            self.par_chunks().for_each(f);
        } else {
            f(self.whole());
        }
    }

    /// The particles in chunks of [`chunk_len`], as a parallel iterator.
    fn par_chunks(&mut self) -> impl rayon::iter::IndexedParallelIterator<Item = ParticleChunk<'_>> {
        use rayon::prelude::*;
        let chunk = chunk_len(self.padded_len());
        (
            self.x.par_chunks_mut(chunk),
            self.y.par_chunks_mut(chunk),
            self.z.par_chunks_mut(chunk),
            self.px.par_chunks_mut(chunk),
            self.py.par_chunks_mut(chunk),
            self.pz.par_chunks_mut(chunk),
            self.vx.par_chunks_mut(chunk),
            self.vy.par_chunks_mut(chunk),
            self.vz.par_chunks_mut(chunk),
            self.w.par_chunks(chunk),
        )
            .into_par_iter()
            .enumerate()
            .map(move |(k, (x, y, z, px, py, pz, vx, vy, vz, w))| ParticleChunk {
                start: k * chunk,
                x,
                y,
                z,
                px,
                py,
                pz,
                vx,
                vy,
                vz,
                w,
            })
    }

    /// All particles as one chunk.
    fn whole(&mut self) -> ParticleChunk<'_> {
        ParticleChunk {
            start: 0,
            x: &mut self.x,
            y: &mut self.y,
            z: &mut self.z,
            px: &mut self.px,
            py: &mut self.py,
            pz: &mut self.pz,
            vx: &mut self.vx,
            vy: &mut self.vy,
            vz: &mut self.vz,
            w: &self.w,
        }
    }
}

impl<'a> ParticleChunk<'a> {
    /// The chunk's first `at` particles and the rest (`at` at most the chunk's length).
    pub fn split_at(self, at: usize) -> (ParticleChunk<'a>, ParticleChunk<'a>) {
        let (x, x1) = self.x.split_at_mut(at);
        let (y, y1) = self.y.split_at_mut(at);
        let (z, z1) = self.z.split_at_mut(at);
        let (px, px1) = self.px.split_at_mut(at);
        let (py, py1) = self.py.split_at_mut(at);
        let (pz, pz1) = self.pz.split_at_mut(at);
        let (vx, vx1) = self.vx.split_at_mut(at);
        let (vy, vy1) = self.vy.split_at_mut(at);
        let (vz, vz1) = self.vz.split_at_mut(at);
        let (w, w1) = self.w.split_at(at);
        let start = self.start;
        (
            ParticleChunk {
                start,
                x,
                y,
                z,
                px,
                py,
                pz,
                vx,
                vy,
                vz,
                w,
            },
            ParticleChunk {
                start: start + at,
                x: x1,
                y: y1,
                z: z1,
                px: px1,
                py: py1,
                pz: pz1,
                vx: vx1,
                vy: vy1,
                vz: vz1,
                w: w1,
            },
        )
    }
}

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
        ParticleChunk {
            start: range.start,
            x: a(0),
            y: a(1),
            z: a(2),
            px: a(3),
            py: a(4),
            pz: a(5),
            vx: a(6),
            vy: a(7),
            vz: a(8),
            // SAFETY: in bounds; only read.
            w: unsafe { std::slice::from_raw_parts(self.w.add(range.start), n) },
        }
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

impl ParticleChunk<'_> {
    /// The same chunk, borrowed again (to hand it to one kernel and keep it for the next).
    pub fn reborrow(&mut self) -> ParticleChunk<'_> {
        ParticleChunk {
            start: self.start,
            x: self.x,
            y: self.y,
            z: self.z,
            px: self.px,
            py: self.py,
            pz: self.pz,
            vx: self.vx,
            vy: self.vy,
            vz: self.vz,
            w: self.w,
        }
    }

    /// The chunk's positions and velocities, `x, y, z, vx, vy, vz`.
    pub fn state(&self) -> [&[f32]; 6] {
        [&*self.x, &*self.y, &*self.z, &*self.vx, &*self.vy, &*self.vz]
    }

    /// Copies the chunk's [`state`](Self::state) into `saved` (six arrays of its length).
    pub fn save_state(&self, saved: [&mut [f32]; 6]) {
        for (dst, src) in saved.into_iter().zip(self.state()) {
            dst.copy_from_slice(src);
        }
    }
}

impl Particles {
    /// [`for_chunks`](Self::for_chunks), also handing each chunk its part of `saved` (six
    /// arrays, resized to the padded length): for a kernel that keeps a copy of the chunk's
    /// state (`x, y, z, vx, vy, vz`) before it changes it. Allocates only when `saved` is not
    /// yet sized.
    pub fn for_chunks_saving<F>(&mut self, parallel: bool, saved: &mut [Vec<f32>; 6], f: F)
    where
        F: Fn(ParticleChunk<'_>, [&mut [f32]; 6]) + Sync + Send,
    {
        use rayon::prelude::*;
        let len = self.padded_len();
        for s in saved.iter_mut() {
            s.resize(len, 0.0);
        }
        let [s0, s1, s2, s3, s4, s5] = saved;
        if parallel && len > CHUNK {
            let chunk = chunk_len(len);
            let parts = (
                s0.par_chunks_mut(chunk),
                s1.par_chunks_mut(chunk),
                s2.par_chunks_mut(chunk),
                s3.par_chunks_mut(chunk),
                s4.par_chunks_mut(chunk),
                s5.par_chunks_mut(chunk),
            )
                .into_par_iter();
            self.par_chunks()
                .zip(parts)
                .for_each(|(chunk, (a, b, c, d, e, g))| f(chunk, [a, b, c, d, e, g]));
        } else {
            f(self.whole(), [s0, s1, s2, s3, s4, s5]);
        }
    }
}

/// Are the first `n` values of every array in `arrays` finite? Eight lanes at once: a sum of
/// `v - v` over the values stays `0` while every value is finite and turns NaN at the first
/// infinity or NaN (`inf - inf` and `NaN - NaN` are NaN), so the loop has no branch. Four
/// sums take the lane groups in turn, so that no add waits for the one before (a single sum
/// waits an add's latency every eight values). A tail of fewer than eight values is checked
/// one by one.
#[allow(clippy::eq_op)] // `v - v` is the test: 0 for a finite value, NaN otherwise
pub fn chunk_finite_simd(arrays: &[&[f32]], n: usize) -> bool {
    use crate::data::lanes::{load, F32s, LANES};
    const SUMS: usize = 4;
    let whole = n - n % LANES;
    let mut acc = [F32s::ZERO; SUMS];
    for a in arrays {
        let mut runs = a[..whole].chunks_exact(SUMS * LANES);
        for run in &mut runs {
            for (s, g) in acc.iter_mut().zip(run.chunks_exact(LANES)) {
                let v = load(g, 0);
                *s += v - v;
            }
        }
        for (s, g) in acc.iter_mut().zip(runs.remainder().chunks_exact(LANES)) {
            let v = load(g, 0);
            *s += v - v;
        }
    }
    let tail_finite = arrays.iter().all(|a| a[whole..n].iter().all(|v| v.is_finite()));
    acc.iter().all(|s| s.to_array().iter().all(|&v| v == 0.0)) && tail_finite
}

/// Scalar twin of [`chunk_finite_simd`].
pub fn chunk_finite_scalar(arrays: &[&[f32]], n: usize) -> bool {
    arrays.iter().all(|a| a[..n].iter().all(|v| v.is_finite()))
}
