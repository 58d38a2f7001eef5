//! How a kernel runs: the one execution choice the world hands down to its stages.

/// Lane width and threads of a kernel call. The world derives it once a step from
/// [`Backend`](crate::model::params::Backend) and its thread setting; every variant gives the
/// same bits (the scalar twins and the SIMD kernels agree, and chunking never changes a result).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Exec {
    /// The scalar twins on the calling thread (`Backend::Scalar`).
    Scalar,
    /// The eight-lane kernels on the calling thread (a world kept on its caller's thread).
    Simd,
    /// The eight-lane kernels in parallel chunks on the current rayon pool (the default).
    Parallel,
    /// The scalar twins in parallel chunks: no world runs this way; tests use it to show that
    /// a scalar twin does not depend on the chunking either.
    ScalarParallel,
}

impl Exec {
    /// The variant with these lane and thread choices.
    pub fn new(simd: bool, parallel: bool) -> Exec {
        match (simd, parallel) {
            (false, false) => Exec::Scalar,
            (true, false) => Exec::Simd,
            (true, true) => Exec::Parallel,
            (false, true) => Exec::ScalarParallel,
        }
    }

    /// Eight-lane kernels (otherwise the scalar twins).
    pub fn simd(self) -> bool {
        matches!(self, Exec::Simd | Exec::Parallel)
    }

    /// Parallel chunks on the current rayon pool (otherwise the calling thread).
    pub fn parallel(self) -> bool {
        matches!(self, Exec::Parallel | Exec::ScalarParallel)
    }
}
