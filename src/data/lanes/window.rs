//! The permutations of a window of sixteen consecutive particles into the `a` and `b` lanes
//! of eight constraints, and back.

use super::{F32s, Vec3x8, LANES};

/// Lane positions in a window of two lane groups: entry `l` (0..16) names element `l % 8` of
/// the low (`l < 8`) or high group.
pub type Pos8 = [u32; LANES];

/// Picks from the 16-element window `lo ‖ hi`: lane `l` of the result is element `pos[l]`.
/// Pure data movement (no rounding), so it cannot change a result bit. On AVX2 this is two
/// `vpermps` and one `vblendvps`; elsewhere a portable array version.
#[inline(always)]
pub fn pick16(lo: F32s, hi: F32s, pos: &Pos8) -> F32s {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    {
        use std::arch::x86_64::{__m256, __m256i, _mm256_blendv_ps, _mm256_castsi256_ps, _mm256_permutevar8x32_ps, _mm256_slli_epi32};
        let idx: __m256i = bytemuck::cast(*pos);
        let lo: __m256 = bytemuck::cast(lo);
        let hi: __m256 = bytemuck::cast(hi);
        // SAFETY: the cfg guarantees AVX2 at compile time; these are register-only intrinsics.
        let r = unsafe {
            // Bit 3 of the position (high group) moved to the sign bit selects the blend.
            let high = _mm256_castsi256_ps(_mm256_slli_epi32::<28>(idx));
            _mm256_blendv_ps(_mm256_permutevar8x32_ps(lo, idx), _mm256_permutevar8x32_ps(hi, idx), high)
        };
        bytemuck::cast(r)
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
    {
        let (lo, hi) = (lo.to_array(), hi.to_array());
        let mut v = [0.0f32; LANES];
        for l in 0..LANES {
            let q = pos[l] as usize & 15;
            v[l] = if q < LANES { lo[q] } else { hi[q - LANES] };
        }
        F32s::from(v)
    }
}

/// [`pick16`] on each component of two 3-vector groups.
#[inline(always)]
pub fn pick16_vec(lo: Vec3x8, hi: Vec3x8, pos: &Pos8) -> Vec3x8 {
    Vec3x8 {
        x: pick16(lo.x, hi.x, pos),
        y: pick16(lo.y, hi.y, pos),
        z: pick16(lo.z, hi.z, pos),
    }
}

/// How [`split16`] deals a window of sixteen consecutive values into two lane groups `a` and
/// `b`, with in-lane shuffles only: lane `l` of `a` is window element [`split_a`]`(l)`, and
/// lane `l` of `b` is the element `stride` further on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Split {
    /// Pairs `(i, i + 1)` for even `i`: stride 1.
    Pairs,
    /// Pairs `(i, i + 2)` for `i mod 4` in `0, 1`: stride 2.
    Quads,
}

/// Window element of lane `l` of a split's `a` group (see [`Split`]): the lanes hold the
/// window's eight pairs in the order `0, 1, 4, 5, 2, 3, 6, 7`.
pub const fn split_a(split: Split, l: usize) -> usize {
    const PAIRS: [usize; LANES] = [0, 2, 8, 10, 4, 6, 12, 14];
    const QUADS: [usize; LANES] = [0, 1, 8, 9, 4, 5, 12, 13];
    match split {
        Split::Pairs => PAIRS[l],
        Split::Quads => QUADS[l],
    }
}

/// The stride between a split's `a` and `b` elements.
pub const fn split_stride(split: Split) -> usize {
    match split {
        Split::Pairs => 1,
        Split::Quads => 2,
    }
}

/// Deals the window `lo ‖ hi` into `(a, b)` (see [`Split`]). Pure data movement: two
/// `vshufps` on AVX; elsewhere a portable array version.
#[inline(always)]
pub fn split16(lo: F32s, hi: F32s, split: Split) -> (F32s, F32s) {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    {
        use std::arch::x86_64::{__m256, _mm256_shuffle_ps};
        let (lo, hi): (__m256, __m256) = (bytemuck::cast(lo), bytemuck::cast(hi));
        // SAFETY: the cfg guarantees AVX at compile time; register-only intrinsics.
        let (a, b) = unsafe {
            match split {
                Split::Pairs => (_mm256_shuffle_ps::<0x88>(lo, hi), _mm256_shuffle_ps::<0xDD>(lo, hi)),
                Split::Quads => (_mm256_shuffle_ps::<0x44>(lo, hi), _mm256_shuffle_ps::<0xEE>(lo, hi)),
            }
        };
        (bytemuck::cast(a), bytemuck::cast(b))
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
    {
        let (lo, hi) = (lo.to_array(), hi.to_array());
        let at = |q: usize| if q < LANES { lo[q] } else { hi[q - LANES] };
        let a: [f32; LANES] = std::array::from_fn(|l| at(split_a(split, l)));
        let b: [f32; LANES] = std::array::from_fn(|l| at(split_a(split, l) + split_stride(split)));
        (F32s::from(a), F32s::from(b))
    }
}

/// The inverse of [`split16`]: the window `(lo, hi)` that `a` and `b` came from.
#[inline(always)]
pub fn merge16(a: F32s, b: F32s, split: Split) -> (F32s, F32s) {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
    {
        use std::arch::x86_64::{__m256, _mm256_shuffle_ps, _mm256_unpackhi_ps, _mm256_unpacklo_ps};
        let (a, b): (__m256, __m256) = (bytemuck::cast(a), bytemuck::cast(b));
        // SAFETY: the cfg guarantees AVX at compile time; register-only intrinsics.
        let (lo, hi) = unsafe {
            match split {
                Split::Pairs => (_mm256_unpacklo_ps(a, b), _mm256_unpackhi_ps(a, b)),
                Split::Quads => (_mm256_shuffle_ps::<0x44>(a, b), _mm256_shuffle_ps::<0xEE>(a, b)),
            }
        };
        (bytemuck::cast(lo), bytemuck::cast(hi))
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
    {
        let (a, b) = (a.to_array(), b.to_array());
        let mut w = [0.0f32; 2 * LANES];
        for l in 0..LANES {
            w[split_a(split, l)] = a[l];
            w[split_a(split, l) + split_stride(split)] = b[l];
        }
        let lo: [f32; LANES] = std::array::from_fn(|q| w[q]);
        let hi: [f32; LANES] = std::array::from_fn(|q| w[LANES + q]);
        (F32s::from(lo), F32s::from(hi))
    }
}

/// [`split16`] on each component of a window of 3-vectors.
#[inline(always)]
pub fn split16_vec(lo: Vec3x8, hi: Vec3x8, split: Split) -> (Vec3x8, Vec3x8) {
    let (ax, bx) = split16(lo.x, hi.x, split);
    let (ay, by) = split16(lo.y, hi.y, split);
    let (az, bz) = split16(lo.z, hi.z, split);
    (Vec3x8 { x: ax, y: ay, z: az }, Vec3x8 { x: bx, y: by, z: bz })
}

/// [`merge16`] on each component.
#[inline(always)]
pub fn merge16_vec(a: Vec3x8, b: Vec3x8, split: Split) -> (Vec3x8, Vec3x8) {
    let (lx, hx) = merge16(a.x, b.x, split);
    let (ly, hy) = merge16(a.y, b.y, split);
    let (lz, hz) = merge16(a.z, b.z, split);
    (Vec3x8 { x: lx, y: ly, z: lz }, Vec3x8 { x: hx, y: hy, z: hz })
}
