//! Seeded xorshift numbers for the unit tests' random inputs: one generator for every module.

/// Uniform in [0, 1) from `seed`. Xorshift stays at zero from a zero state (every number
/// would be 0), so a zero seed is replaced by a fixed non-zero one: property tests draw seeds
/// from ranges that include 0.
pub(crate) fn unit(seed: u64) -> impl FnMut() -> f32 {
    let mut s = if seed == 0 { 0x9E37_79B9_7F4A_7C15 } else { seed };
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Uniform in [-1, 1) from `seed` (as [`unit`]).
pub(crate) fn signed(seed: u64) -> impl FnMut() -> f32 {
    let mut u = unit(seed);
    move || u() * 2.0 - 1.0
}

/// Values the property tests put in place of random ones: non-finite, huge, a signed zero and a
/// subnormal (the lanes and their scalar twins must treat them alike).
pub(crate) const SPECIAL_F32: [f32; 6] = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e30, -0.0, f32::from_bits(3)];

/// Up to five replacements `(index, array, value)`: a raw index (taken modulo the length), one
/// of `arrays` arrays and an index into [`SPECIAL_F32`].
pub(crate) fn specials(arrays: usize) -> impl proptest::strategy::Strategy<Value = Vec<(u16, usize, usize)>> {
    proptest::collection::vec((proptest::prelude::any::<u16>(), 0..arrays, 0..SPECIAL_F32.len()), 0..6)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A zero seed gives varying numbers in [0, 1), not xorshift's fixed zero.
    #[test]
    fn a_zero_seed_still_varies() {
        let mut u = unit(0);
        let first = u();
        let rest: Vec<f32> = (0..16).map(|_| u()).collect();
        assert!(rest.iter().any(|&v| v != first), "{first} {rest:?}");
        assert!(rest.iter().all(|v| (0.0..1.0).contains(v)));
    }
}
