//! The neighbour predicate every broadphase shares (stated in the docs of
//! [`neighbours`](super)), the search box that finds every pair it accepts despite rounding,
//! the checks of a query's arguments, and [`Candidates`], the lane scan of contiguous
//! candidates under the predicate.

use crate::data::lanes::{F32s, Vec3x8, LANES};
use crate::{Result, WeftError};

/// Candidate particles stored contiguously: ids with their positions at the same index. The
/// position arrays extend at least [`LANES`] entries past any scanned range (NaN padding), so a
/// lane load never leaves them.
pub(crate) struct Candidates<'a> {
    pub ids: &'a [u32],
    pub x: &'a [f32],
    pub y: &'a [f32],
    pub z: &'a [f32],
    /// Keep only ids above the skipped one (each pair once, in the list of its smaller id).
    pub above: bool,
}

impl Candidates<'_> {
    /// Whether id `j` may be listed for particle `skip`.
    #[inline(always)]
    fn keeps(&self, j: u32, skip: u32) -> bool {
        if self.above {
            j > skip
        } else {
            j != skip
        }
    }

    /// Appends to `buf` each `ids[k]`, `k` in `range`, other than `skip` (above it with
    /// [`Candidates::above`]), whose position passes
    /// the predicate against `p`. With `SIMD` eight candidates are tested per lane load, the
    /// predicate computed operation for operation like [`within`] (no FMA), so both paths pick
    /// the same ids; without it, the plain scalar loop (the twin).
    #[inline(always)]
    pub fn scan<const SIMD: bool>(&self, range: std::ops::Range<usize>, skip: u32, p: [f32; 3], md2: f32, buf: &mut Vec<u32>) {
        let (s, e) = (range.start, range.end);
        if !SIMD {
            for k in s..e {
                let j = self.ids[k];
                if self.keeps(j, skip) && within(p[0], p[1], p[2], self.x[k], self.y[k], self.z[k], md2) {
                    buf.push(j);
                }
            }
            return;
        }
        let (pv, m2) = (Vec3x8::splat(p), F32s::splat(md2));
        let mut k = s;
        while k < e {
            let d = Vec3x8::load(self.x, self.y, self.z, k) - pv;
            let d2 = d.x * d.x + d.y * d.y + d.z * d.z;
            let mut bits = d2.simd_le(m2).to_bitmask();
            if e - k < LANES {
                bits &= (1u32 << (e - k)) - 1;
            }
            while bits != 0 {
                let j = self.ids[k + bits.trailing_zeros() as usize];
                bits &= bits - 1;
                if self.keeps(j, skip) {
                    buf.push(j);
                }
            }
            k += LANES;
        }
    }
}

/// The neighbour predicate (see the module docs), shared by every broadphase.
#[inline(always)]
pub(crate) fn within(xi: f32, yi: f32, zi: f32, xj: f32, yj: f32, zj: f32, md2: f32) -> bool {
    let dx = xj - xi;
    let dy = yj - yi;
    let dz = zj - zi;
    dx * dx + dy * dy + dz * dz <= md2
}

/// The squared reach of a pair whose particles travel `ti` and `tj` collision distances `d`
/// in a step: `(d + (t_i + t_j) d)²`, computed in this order everywhere (lanes and scalar).
#[inline(always)]
pub(crate) fn pair_reach2(d: f32, ti: f32, tj: f32) -> f32 {
    let r = d + (ti + tj) * d;
    r * r
}

/// Half-width of the box a broadphase must search around a particle so that it finds every
/// `j` that passes [`within`] despite rounding: if the `f32` test passes, the exact distance
/// along each axis is at most `max(max_dist * (1 + 2^-22), 1.1e-19)` (the second term covers
/// squares that underflow). The returned value exceeds both bounds.
#[inline]
pub(crate) fn search_radius(max_dist: f32) -> f32 {
    max_dist * (1.0 + 1.0 / 1_048_576.0) + 2e-19
}

/// Validates `max_dist` (finite, not negative) and returns `max_dist²`.
pub(crate) fn check_max_dist(max_dist: f32) -> Result<f32> {
    crate::error::non_negative("max_dist", max_dist)?;
    Ok(max_dist * max_dist)
}

/// Checks that the position arrays hold at least `n` particles and that ids fit in `u32`.
pub(crate) fn check_positions(x: &[f32], y: &[f32], z: &[f32], n: usize) -> Result<()> {
    if n >= u32::MAX as usize {
        return Err(WeftError::param("n", n, "must be below 2^32 - 1 (ids are u32)"));
    }
    for (name, a) in [("x", x), ("y", y), ("z", z)] {
        if a.len() < n {
            return Err(WeftError::BufferLength {
                name,
                got: a.len(),
                expected: n,
            });
        }
    }
    Ok(())
}
