//! Seeded xorshift numbers for the unit tests' random inputs: one generator for every module.

/// Uniform in [0, 1); `seed` must be non-zero (callers pass e.g. `seed | 1`).
pub(crate) fn unit(seed: u64) -> impl FnMut() -> f32 {
    let mut s = seed;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Uniform in [-1, 1); `seed` must be non-zero.
pub(crate) fn signed(seed: u64) -> impl FnMut() -> f32 {
    let mut u = unit(seed);
    move || u() * 2.0 - 1.0
}
