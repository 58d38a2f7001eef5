//! The chunked passes over [`Particles`]: [`ParticleChunk`], a contiguous range handed to an
//! element-wise kernel, the passes that run a kernel over chunks of [`chunk_len`] particles
//! (serially or on the rayon pool; the same bits either way), and the guard's finite check of
//! a chunk ([`chunk_finite_simd`] and its scalar twin).

use super::Particles;

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
    /// either way. Two chunks run as one `rayon::join`, one task for the other thread to take.
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
            .map(move |(k, (x, y, z, px, py, pz, vx, vy, vz, w))| {
                ParticleChunk::from_arrays(k * chunk, [x, y, z, px, py, pz, vx, vy, vz], w)
            })
    }

    /// All particles as one chunk.
    fn whole(&mut self) -> ParticleChunk<'_> {
        let a = [
            &mut self.x,
            &mut self.y,
            &mut self.z,
            &mut self.px,
            &mut self.py,
            &mut self.pz,
            &mut self.vx,
            &mut self.vy,
            &mut self.vz,
        ];
        ParticleChunk::from_arrays(0, a.map(|v| &mut v[..]), &self.w)
    }
}

impl<'a> ParticleChunk<'a> {
    /// The chunk of particles from `start` with the arrays `a` (`x, y, z, px, py, pz, vx, vy,
    /// vz`) and inverse masses `w`.
    pub(crate) fn from_arrays(start: usize, a: [&'a mut [f32]; 9], w: &'a [f32]) -> Self {
        let [x, y, z, px, py, pz, vx, vy, vz] = a;
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
        }
    }

    /// The chunk's first `at` particles and the rest (`at` at most the chunk's length).
    pub fn split_at(self, at: usize) -> (ParticleChunk<'a>, ParticleChunk<'a>) {
        let a = [self.x, self.y, self.z, self.px, self.py, self.pz, self.vx, self.vy, self.vz];
        let (mut lo, mut hi): ([&mut [f32]; 9], [&mut [f32]; 9]) = Default::default();
        for ((l, h), v) in lo.iter_mut().zip(&mut hi).zip(a) {
            (*l, *h) = v.split_at_mut(at);
        }
        let (w0, w1) = self.w.split_at(at);
        (Self::from_arrays(self.start, lo, w0), Self::from_arrays(self.start + at, hi, w1))
    }
}

impl ParticleChunk<'_> {
    /// The same chunk, borrowed again (to hand it to one kernel and keep it for the next).
    pub fn reborrow(&mut self) -> ParticleChunk<'_> {
        let a = [
            &mut *self.x,
            &mut *self.y,
            &mut *self.z,
            &mut *self.px,
            &mut *self.py,
            &mut *self.pz,
            &mut *self.vx,
            &mut *self.vy,
            &mut *self.vz,
        ];
        ParticleChunk::from_arrays(self.start, a, self.w)
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
