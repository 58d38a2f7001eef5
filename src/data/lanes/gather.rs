//! Indices a lane and the gathers of read-only arrays by them.

use super::{F32s, LANES};

/// Eight indices into particle arrays, one per lane.
pub type Idx8 = [u32; LANES];

/// Reads `idx` from the first `LANES` entries of `s` starting at `i`.
#[inline(always)]
pub fn load_idx(s: &[u32], i: usize) -> Idx8 {
    s[i..i + LANES].try_into().expect("slice of lane width")
}

/// [`load_idx`] without the bounds check.
///
/// # Safety
/// `i + LANES <= s.len()`.
#[inline(always)]
pub unsafe fn load_idx_unchecked(s: &[u32], i: usize) -> Idx8 {
    debug_assert!(i + LANES <= s.len());
    // SAFETY: the caller guarantees the eight values are inside `s`.
    unsafe { std::ptr::read_unaligned(s.as_ptr().add(i).cast::<Idx8>()) }
}

/// Eight indices `f(0) .. f(7)`, written out (array `map` and `from_fn` can be compiled to
/// out-of-line calls in hot loops, measured in the self-collision pair pass).
#[inline(always)]
pub fn idx8(f: impl Fn(usize) -> u32) -> Idx8 {
    [f(0), f(1), f(2), f(3), f(4), f(5), f(6), f(7)]
}

/// Gathers eight values of a read-only array (bounds-checked), built in registers: on AVX,
/// `_mm256_set_ps` of eight scalar loads (an array on the stack, reloaded as a vector, cost
/// a store-forwarding stall that made the self-collision candidate test twice as slow,
/// measured). Pure data movement: no result bit depends on it. The AVX2 hardware gather
/// (`vgatherdps`) is not used: it was slower than eight scalar loads on Zen 3.
#[inline(always)]
pub fn gather1(s: &[f32], idx: &Idx8) -> F32s {
    // Its own checked loads rather than a check of the largest index and
    // [`gather1_unchecked`]: that cost the distance solve's gathers more instructions.
    let g = |l: usize| s[idx[l] as usize];
    let v = [g(0), g(1), g(2), g(3), g(4), g(5), g(6), g(7)];
    in_registers(v)
}

/// Eight `[x, y, z, w]` records of `xyzw` (indices `idx`) as four vectors: lane `l` of the
/// first holds `xyzw[idx[l]][0]`, and so on. Eight 16-byte loads and a transpose instead of
/// eight scalar loads a component: the gather of the self-collision pair pass, which reads
/// whole positions.
///
/// # Safety
/// Every index of `idx` must be below `xyzw.len()`.
#[inline(always)]
pub unsafe fn gather_xyzw8_unchecked(xyzw: &[[f32; 4]], idx: &Idx8) -> [F32s; 4] {
    // SAFETY: the caller guarantees every index is in bounds.
    let entry = |l: usize| unsafe { *xyzw.get_unchecked(idx[l] as usize) };
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    {
        use std::arch::x86_64::{__m128, __m256, _mm256_set_m128, _mm256_shuffle_ps, _mm256_unpackhi_ps, _mm256_unpacklo_ps};
        let row = |l: usize| -> __m128 { bytemuck::cast(entry(l)) };
        let r = [row(0), row(1), row(2), row(3), row(4), row(5), row(6), row(7)];
        // SAFETY: the cfg guarantees AVX at compile time; register-only intrinsics.
        let (x, y, z, w) = unsafe {
            // Low halves from records 0..4, high halves from records 4..8.
            let a = _mm256_set_m128(r[4], r[0]);
            let b = _mm256_set_m128(r[5], r[1]);
            let c = _mm256_set_m128(r[6], r[2]);
            let d = _mm256_set_m128(r[7], r[3]);
            let lo_ab = _mm256_unpacklo_ps(a, b); // x0 x1 y0 y1 | x4 x5 y4 y5
            let lo_cd = _mm256_unpacklo_ps(c, d); // x2 x3 y2 y3 | x6 x7 y6 y7
            let hi_ab = _mm256_unpackhi_ps(a, b); // z0 z1 w0 w1 | z4 z5 w4 w5
            let hi_cd = _mm256_unpackhi_ps(c, d); // z2 z3 w2 w3 | z6 z7 w6 w7
            (
                _mm256_shuffle_ps::<0x44>(lo_ab, lo_cd),
                _mm256_shuffle_ps::<0xEE>(lo_ab, lo_cd),
                _mm256_shuffle_ps::<0x44>(hi_ab, hi_cd),
                _mm256_shuffle_ps::<0xEE>(hi_ab, hi_cd),
            )
        };
        let c = |v: __m256| -> F32s { bytemuck::cast(v) };
        [c(x), c(y), c(z), c(w)]
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
    {
        let rows: [[f32; 4]; LANES] = std::array::from_fn(entry);
        [0, 1, 2, 3].map(|a| F32s::from(rows.map(|r| r[a])))
    }
}

/// [`gather1`] without the bounds checks.
///
/// # Safety
/// Every index of `idx` must be below `s.len()`.
#[inline(always)]
pub unsafe fn gather1_unchecked(s: &[f32], idx: &Idx8) -> F32s {
    // SAFETY: the caller guarantees every index is in bounds.
    let g = |l: usize| unsafe { *s.get_unchecked(idx[l] as usize) };
    let v = [g(0), g(1), g(2), g(3), g(4), g(5), g(6), g(7)];
    in_registers(v)
}

/// Eight loaded values as a vector built in registers (see [`gather1`]): on AVX
/// `_mm256_set_ps`, elsewhere the portable conversion.
#[inline(always)]
fn in_registers(v: [f32; LANES]) -> F32s {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    {
        use std::arch::x86_64::{__m256, _mm256_set_ps};
        // SAFETY: the cfg guarantees AVX at compile time; register-only intrinsic.
        let r: __m256 = unsafe { _mm256_set_ps(v[7], v[6], v[5], v[4], v[3], v[2], v[1], v[0]) };
        bytemuck::cast(r)
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
    {
        F32s::from(v)
    }
}
