//! Stage 2 of the obstacle step for a mesh obstacle: the contacts of one block of eight
//! particles ([`obstacles`](crate::obstacles) module doc; Landovskaya, Landovsky & Frolovsky).
//!
//! For each live particle of the block (a real particle with inverse mass `w > 0`) the path
//! is `x - u h -> p` in the obstacle's frame and its query box `Q` is the path's box grown by
//! the contact reach ([`query_box`]). Three cases, cheapest first:
//!
//! 1. **Far from the mesh.** Every face's box lies inside the mesh's box, so when `Q` misses
//!    the mesh box on some axis (`Q.hi < lo` or `Q.lo > hi`, exact `f32` comparisons) no face
//!    can overlap `Q`: no contact, and the particle's kept candidate list is not even read.
//!    This is the paper's first test ("is the particle inside the box around the object at
//!    all?") taken per particle. A NaN coordinate never counts as far: such a particle goes
//!    the full way, which finds no contact either.
//! 2. **Kept list** ([`CacheBlock`]): the faces gathered for a box around an earlier path
//!    still cover `Q`, so the narrowphase tests them; when the box was empty of faces there
//!    is nothing to test. That last case is found with case 1, for the eight lanes at once
//!    from the block's gathered boxes and list lengths ([`CacheBlock::held_empty_simd`]),
//!    so such a particle costs no scalar work at all (finite inputs only, as in case 1).
//!    So is a particle whose list's clearance ball has no near face and vouches for the
//!    step ([`CacheBlock::ball_empty_simd`], [`face_ball`](crate::obstacles::mesh::face_ball)); when the
//!    ball has near faces, only they are tested.
//! 3. **Gather**: the broadphase is asked again (and the list kept for the coming steps).
//!
//! With the paper's face memory every live particle runs the memory rule around cases 2-3
//! (a far particle must also forget its face), and the fresh-search reference (no kept lists,
//! no far test) runs the full search for every live particle. All cases give the contacts of
//! the plain search ([`step_contact`](crate::obstacles::mesh::contact::step_contact)), so the pass
//! changes the cost, not the answer; each particle writes only its own slot, list and memory,
//! so the result does not depend on the thread count.
//!
//! The block's slots are cleared, each contact is written into its lane, and the approach
//! speeds are filled only when some lane holds a contact (a block without contact has all
//! approach speeds `0`, as [`fill_approach`](k::fill_approach) would write).

use crate::data::lanes::{load, F32s, Vec3x8, LANES};
use crate::obstacles::kernels::{self as k, GenInput};
use crate::obstacles::mesh::contact::{remembered_with, MeshBroadphase};
use crate::obstacles::mesh::face_cache::CacheBlock;
use crate::obstacles::mesh::narrow::query_box;
use crate::obstacles::mesh::TriMesh;

/// One substep's contact pass of a mesh obstacle (module doc).
pub(crate) struct MeshPass<'a> {
    /// The mesh at its place for this substep.
    pub mesh: &'a TriMesh,
    /// Its broadphase.
    pub bp: &'a MeshBroadphase,
    /// The particles' paths and reaches.
    pub input: GenInput<'a>,
    /// Particle velocities (for the approach speeds).
    pub vel: [&'a [f32]; 3],
    /// The obstacle's velocity.
    pub u: [f32; 3],
    /// Face memory on (the memories are the per-particle `mem` slices).
    pub remember: bool,
    /// Fresh search for every particle: the reference of the kept lists and the far test.
    pub fresh: bool,
    /// Find the lanes to skip with [`skip_lanes_simd`] (else its scalar twin).
    pub simd: bool,
}

/// The eight values of padded array `a` for block `b`.
#[inline]
fn lanes(a: &[f32], b: usize) -> [f32; LANES] {
    let s = &a[b * LANES..(b + 1) * LANES];
    std::array::from_fn(|l| s[l])
}

/// The lanes of block `b` the pass skips, bit `l` for particle `8 b + l`: not live, or every
/// input finite and (with `far`) the query box missing the box `[lo, hi]` on some axis or
/// (with `kept`) the lane's kept list empty with a gathered box holding the query box
/// ([`CacheBlock::held_empty`]), or (with `kept`) the lane's ball empty of near faces
/// and vouching for the step ([`CacheBlock::ball_empty`]). The scalar twin of
/// [`skip_lanes_simd`], built on [`query_box`] itself.
pub(crate) fn skip_lanes(g: &GenInput, b: usize, lo: [f32; 3], hi: [f32; 3], far: bool, kept: Option<&CacheBlock>) -> u32 {
    let (mut skip, mut finite_bits) = (0, 0);
    let (mut qlo, mut qhi) = ([[0.0; LANES]; 3], [[0.0; LANES]; 3]);
    let (mut xs, mut ps, mut reach) = ([[0.0; LANES]; 3], [[0.0; LANES]; 3], [0.0; LANES]);
    for l in 0..LANES {
        let i = b * LANES + l;
        let live = i < g.n && g.w[i] > 0.0;
        let x = [g.x[0][i] - g.shift[0], g.x[1][i] - g.shift[1], g.x[2][i] - g.shift[2]];
        let p = [g.p[0][i], g.p[1][i], g.p[2][i]];
        let finite = x.iter().chain(&p).all(|v| v.is_finite()) && g.reach[i].is_finite();
        let (ql, qh) = query_box(x, p, g.reach[i]);
        for k in 0..3 {
            (qlo[k][l], qhi[k][l]) = (ql[k], qh[k]);
        }
        let miss = (0..3).any(|k| qh[k] < lo[k] || ql[k] > hi[k]);
        if !live || (far && finite && miss) {
            skip |= 1 << l;
        }
        finite_bits |= (finite as u32) << l;
        for k in 0..3 {
            (xs[k][l], ps[k][l]) = (x[k], p[k]);
        }
        reach[l] = g.reach[i];
    }
    skip | kept.map_or(0, |c| (c.held_empty(qlo, qhi) & finite_bits) | c.ball_empty(xs, ps, reach))
}

/// [`skip_lanes`] eight lanes at once. For finite inputs the boxes are those of
/// [`query_box`] (the same operations in the same order; maxima and minima of finite values
/// are exact, and the comparisons do not see the sign of a zero), so the masks agree bit for
/// bit; lanes with a non-finite input are never skipped as far or as held empty.
pub(crate) fn skip_lanes_simd(g: &GenInput, b: usize, lo: [f32; 3], hi: [f32; 3], far: bool, kept: Option<&CacheBlock>) -> u32 {
    let i = b * LANES;
    let x = Vec3x8::load(g.x[0], g.x[1], g.x[2], i) - Vec3x8::splat(g.shift);
    let p = Vec3x8::load(g.p[0], g.p[1], g.p[2], i);
    let reach = load(g.reach, i);
    let zero = F32s::splat(0.0);
    let index = F32s::from(std::array::from_fn::<f32, LANES, _>(|l| l as f32));
    let real = index.simd_lt(F32s::splat(g.n.saturating_sub(i).min(LANES) as f32));
    let live = real & load(g.w, i).simd_gt(zero);
    let mut skip = !live.to_bitmask() & 0xff;
    if far || kept.is_some() {
        let big = zero
            .max(x.x.abs())
            .max(x.y.abs())
            .max(x.z.abs())
            .max(p.x.abs())
            .max(p.y.abs())
            .max(p.z.abs());
        let grow = reach + F32s::splat(crate::obstacles::mesh::narrow::QUERY_PAD) * (F32s::splat(1.0) + big);
        let finite =
            x.x.is_finite() & x.y.is_finite() & x.z.is_finite() & p.x.is_finite() & p.y.is_finite() & p.z.is_finite() & reach.is_finite();
        let qlo = Vec3x8 {
            x: x.x.min(p.x) - grow,
            y: x.y.min(p.y) - grow,
            z: x.z.min(p.z) - grow,
        };
        let qhi = Vec3x8 {
            x: x.x.max(p.x) + grow,
            y: x.y.max(p.y) + grow,
            z: x.z.max(p.z) + grow,
        };
        if far {
            let axis = |l: F32s, h: F32s, k: usize| h.simd_lt(F32s::splat(lo[k])) | l.simd_gt(F32s::splat(hi[k]));
            let miss = axis(qlo.x, qhi.x, 0) | axis(qlo.y, qhi.y, 1) | axis(qlo.z, qhi.z, 2);
            skip |= (finite & miss).to_bitmask();
        }
        if let Some(c) = kept {
            skip |= (c.held_empty_simd(qlo, qhi) & finite.to_bitmask()) | c.ball_empty_simd(x, p, reach);
        }
    }
    skip
}

impl MeshPass<'_> {
    /// The contacts of block `b` into `out` (the block's slot floats); `mem` and `cache` are
    /// the block's face memories (empty without memory) and kept lists (eight entries).
    pub(crate) fn block(
        &self,
        b: usize,
        out: &mut [f32],
        was: bool,
        mem: &mut [u32],
        cache: &mut CacheBlock,
        scratch: &mut Vec<u32>,
    ) -> bool {
        let g = &self.input;
        let (mlo, mhi) = self.mesh.bounds();
        let skip_far = !self.remember && !self.fresh;
        let kept = skip_far.then_some(&*cache);
        let skip = if self.simd {
            skip_lanes_simd(g, b, mlo, mhi, skip_far, kept)
        } else {
            skip_lanes(g, b, mlo, mhi, skip_far, kept)
        };
        // `was`: the block held a contact before this pass (else it is all +0.0 already).
        if was {
            out.fill(0.0);
        }
        if skip == 0xff {
            return false;
        }
        let x = [lanes(g.x[0], b), lanes(g.x[1], b), lanes(g.x[2], b)];
        let p = [lanes(g.p[0], b), lanes(g.p[1], b), lanes(g.p[2], b)];
        let sh = g.shift;
        let reach = lanes(g.reach, b);
        let mut touched = false;
        for l in 0..LANES {
            if skip & (1 << l) != 0 {
                continue;
            }
            let xl = [x[0][l] - sh[0], x[1][l] - sh[1], x[2][l] - sh[2]];
            let pl = [p[0][l], p[1][l], p[2][l]];
            let (lo, hi) = query_box(xl, pl, reach[l]);
            let mut search = || cache.contact_in(l, self.mesh, self.bp, xl, pl, reach[l], (lo, hi), !self.fresh, scratch);
            let c = if self.remember {
                remembered_with(self.mesh, &mut mem[l], xl, pl, reach[l], 2.0 * reach[l], search)
            } else {
                search()
            };
            if let Some(c) = c {
                k::write_slot(out, l, c.point, c.normal);
                touched = true;
            }
        }
        if touched {
            k::fill_approach(out, b, self.vel, self.u);
            k::block_nonzero(out)
        } else {
            false
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::obstacles::mesh::broadphase::BruteForce;
    use crate::obstacles::mesh::contact::step_contact;

    /// The SIMD lane mask equals its scalar twin on random blocks with non-finite values,
    /// pinned particles, padding and kept lists (gathered for the lane's own path on some
    /// lanes, never on others); a lane called far has no face of a mesh inside `[lo, hi]`
    /// within reach, and a lane skipped as held empty has no contact in a fresh search.
    #[test]
    fn skip_masks_agree_and_skipped_lanes_touch_nothing() {
        let mesh = crate::obstacles::mesh::dressform::dress_form(600).unwrap();
        let bp = BruteForce::new(&mesh);
        let (lo, hi) = mesh.bounds();
        let mut r = crate::test_rng::unit(5);
        let len = 64 * LANES;
        let mut v = |scale: f32| -> Vec<f32> { (0..len).map(|_| (r() - 0.3) * scale).collect() };
        let (mut x, y, z) = (v(1.0), v(2.0), v(1.0));
        // short paths (so that kept boxes stay small) and positive reaches
        let (dx, dy, dz) = (v(0.02), v(0.02), v(0.02));
        let step = |a: &[f32], d: &[f32]| -> Vec<f32> { a.iter().zip(d).map(|(a, d)| a + d).collect() };
        let (mut px, py, pz) = (step(&x, &dx), step(&y, &dy), step(&z, &dz));
        let (mut w, reach) = (v(1.0), v(0.01).iter().map(|r| r + 0.005).collect::<Vec<f32>>());
        for (i, special) in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -0.0, 0.0, f32::MAX]
            .into_iter()
            .enumerate()
        {
            x[7 * i + 3] = special;
            px[11 * i + 5] = special;
            w[13 * i + 1] = special;
        }
        let th = vec![0.001; len];
        let (mut far, mut empty, mut kept, mut balls) = (0, 0, 0, 0);
        for n in [len, len - 3] {
            let g = GenInput {
                x: [&x, &y, &z],
                p: [&px, &py, &pz],
                w: &w,
                th: &th,
                reach: &reach,
                n,
                shift: [0.01, -0.02, 0.0],
            };
            for b in 0..len / LANES {
                let mut cache = CacheBlock::default();
                for l in (0..LANES).filter(|l| (b + l) % 3 != 0) {
                    let (xl, pl) = g.path(b * LANES + l);
                    cache.step_contact(l, &mesh, &bp, xl, pl, reach[b * LANES + l], true, &mut Vec::new());
                }
                for check in [false, true] {
                    for c in [None, Some(&cache)] {
                        let s = skip_lanes(&g, b, lo, hi, check, c);
                        assert_eq!(s, skip_lanes_simd(&g, b, lo, hi, check, c), "block {b} far {check}");
                        let far_only = skip_lanes(&g, b, lo, hi, check, None);
                        for l in 0..LANES {
                            let i = b * LANES + l;
                            if s & (1 << l) == 0 || !g.live(i) {
                                kept += 1;
                                continue;
                            }
                            let (xl, pl) = g.path(i);
                            let (ql, qh) = query_box(xl, pl, reach[i]);
                            if far_only & (1 << l) != 0 {
                                far += 1;
                                assert!((0..mesh.face_count() as u32).all(|f| !mesh.face_overlaps(f, ql, qh)));
                            } else {
                                empty += 1;
                                // skipped with a non-empty list: its ball vouched
                                balls += c.is_some_and(|c| !c.faces(l).is_empty()) as usize;
                                assert_eq!(step_contact(&mesh, &bp, xl, pl, reach[i], &mut Vec::new()), None);
                            }
                        }
                    }
                }
            }
        }
        assert!(far > 100 && empty > 100 && kept > 100 && balls > 20, "{far} {empty} {kept} {balls}");
    }
}
