//! The lane vocabulary: the only module that knows the SIMD width.
//!
//! Kernels are written over [`Vec3x8`] (eight 3-vectors in three `f32x8` registers) and read
//! like the math. Particle arrays are padded to a multiple of [`LANES`] so that hot loops have
//! no scalar tail. The unchecked loads, gathers and scatters, and the shared write handle
//! [`SharedVec3`], are defined here with their safety contracts; their callers (the
//! constraint, spring and self-collision kernels) check the indices once before using them.
//!
//! No kernel uses fused multiply-add: `a * b + c` rounds twice in both the SIMD kernels and
//! their scalar twins, so the two agree bit for bit whatever target features the build enables.

use wide::f32x8;

/// Number of `f32` lanes a kernel processes at once.
pub const LANES: usize = 8;

/// The lane type.
pub type F32s = f32x8;

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

/// The lanes of `v` that are finite (`|v| < inf` fails exactly for NaN and ±inf), as a mask.
#[inline(always)]
pub fn finite_lanes(v: F32s) -> F32s {
    v.abs().simd_lt(F32s::splat(f32::INFINITY))
}

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

#[cfg(test)]
#[path = "lanes_tests.rs"]
mod tests;
