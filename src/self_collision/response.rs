//! The velocity-correction pass of self-collision over the particle arrays (after Shapri,
//! Sulaiman & Bade 2016, "Velocity Correction Position Based Dynamic to optimize collision
//! computation in cloth simulation", and Müller's "Ten Minute Physics" self-collision): SIMD
//! (`f32x8`) with a scalar twin that the tests hold to it bit for bit (same operations in the
//! same order, no FMA). The speed clamp that runs before it is in [`super::clamp`].
//!
//! # Velocity correction (VcCPBD, Algorithm 2; Müller's friction)
//! The pair pass ([`crate::self_collision`]) leaves, per particle `i`, one [`Record`] of the
//! sums over its contacts of: the position correction `c`, the partners' displacements
//! `f = Σ (p_j - x_j)`, the unit contact normals `n` (pointing away from the partners), the
//! signed gaps `g` (`dist - min_dist`, negative in contact), the contact count `k` and the
//! approaching count (movement speed: `c` is averaged over those, [`corrections`]). This
//! kernel applies them
//! to a free particle with `k > 0` (Jacobi, averaged over the contacts and over-relaxed by
//! `ω =` [`RELAXATION`]):
//!
//! ```text
//! t = p + ω c / k + μ (f / k - (p - x)) / 2        projection + friction (all responses)
//! VcCPBD only, with q the predicted position (after the clamp), r the box radius (the
//! collision distance d), n̂ = n / |n|, e = g / k:
//!   if |t - q| >= r:  p = q                          back to the centre of the particle's box
//!   else:             β = min(b h, 1)
//!                     p = t - (β (t - x)·n̂ + β² e / 4) n̂
//! ```
//!
//! Our reading of the paper's box: the particle's bounding box of radius `r` centred on where
//! inertia alone takes it this substep, `c = (max + min) / 2 = q`; `s = |t - q|` is how far
//! the solver moved it. With no obstacles nothing changes the predictions or the velocities
//! between predict and the speed clamp, so `q = x + h v` exactly (both compute it so) and the
//! kernel derives it ([`ApplyInput::v`]) instead of reading a copy the clamp made of every
//! active particle each substep. A particle pushed out of its box is put back to the centre (a guard
//! against the overshooting corrections of tangled layers); inside it, the velocity is
//! corrected. The VcCPBD line is the paper's velocity correction `v <- (p - δd) + a dt`, `x <- p` written
//! on positions (the update stage then sets `v = (p - x) / h`): the damped oscillator
//! `δd = m x'' + k x + b x'` per unit mass along the contact normal, with `b` the fabric's
//! damping rate (the paper's damping column), `k/m = b²/4` (critical damping, the paper gives
//! no stiffness), `x'` the normal velocity `(t - x)·n̂ / h` and `x` the mean gap `e`; the
//! `m x'' = a` term is the external acceleration of the next substep, which predict adds, so it
//! is not added twice here. `β = min(b h, 1)` keeps the correction from overshooting.

use crate::data::lanes::{load, load_unchecked, store, store_unchecked, F32s, Vec3x8, LANES};
use crate::model::self_collision::{Response, RELAXATION};
use crate::model::shapes::dot;
use crate::self_collision::pass::sums::transpose_records;
pub use crate::self_collision::pass::sums::{corrections, Record, RECORD};

/// Inputs of [`apply`] for one chunk of particles starting at global index `start`.
pub struct ApplyInput<'a> {
    /// Global index of the chunk's first particle.
    pub start: usize,
    /// Positions at the start of the substep.
    pub x: [&'a [f32]; 3],
    /// Inverse masses.
    pub w: &'a [f32],
    /// Predicted positions (box centres), global indexing.
    pub q: [&'a [f32]; 3],
    /// Velocities of the substep, indexed like `x`: when given, the box centres are
    /// `x + h v` (the predictions as predict and the speed clamp compute them) and `q` is
    /// not read.
    pub v: Option<[&'a [f32]; 3]>,
    /// Damping rates `b`, 1/s, global indexing.
    pub b: &'a [f32],
    /// Contact sums, one record a particle, global indexing.
    pub sums: &'a [Record],
    /// Friction `μ` in `[0, 1]`.
    pub friction: f32,
    /// Substep length, s.
    pub h: f32,
    /// Box radius `r`, m.
    pub r: f32,
}

/// Applies the contact sums to the predicted positions `p` of one chunk (lengths a multiple of
/// [`LANES`]): SIMD when `simd`, else the scalar twin. Same bits either way.
pub fn apply(inp: &ApplyInput<'_>, p: [&mut [f32]; 3], response: Response, simd: bool) {
    match (response, simd) {
        (Response::Vccpbd, true) => apply_simd::<true>(inp, p),
        (_, true) => apply_simd::<false>(inp, p),
        (r, false) => apply_scalar(inp, p, r == Response::Vccpbd),
    }
}

/// Runs of blocks of [`apply_runs`]: `(k, b, len)` = compact block `k` (the sums' index over
/// [`LANES`]) holds particle block `b`, for `len` consecutive blocks of both.
pub(crate) type Run = (usize, usize, usize);

/// The kernel on runs of blocks, `x`, `w` and `p` the whole particle arrays (`inp.start`
/// unused): per lane the operations of [`apply`] (the same bits), with the constants set up
/// once for all runs instead of once a call. The scalar backend calls the scalar twin on
/// each run.
pub(crate) fn apply_runs(inp: &ApplyInput<'_>, p: [&mut [f32]; 3], runs: impl Iterator<Item = Run>, response: Response, simd: bool) {
    let [px, py, pz] = p;
    match (response, simd) {
        (Response::Vccpbd, true) => runs_simd::<true>(inp, [px, py, pz], runs),
        (_, true) => runs_simd::<false>(inp, [px, py, pz], runs),
        (m, false) => {
            for (k, b, len) in runs {
                let g = b * LANES..(b + len) * LANES;
                let one = ApplyInput {
                    start: k * LANES,
                    x: [&inp.x[0][g.clone()], &inp.x[1][g.clone()], &inp.x[2][g.clone()]],
                    w: &inp.w[g.clone()],
                    v: inp.v.map(|v| [&v[0][g.clone()], &v[1][g.clone()], &v[2][g.clone()]]),
                    ..*inp
                };
                apply_scalar(&one, [&mut px[g.clone()], &mut py[g.clone()], &mut pz[g]], m == Response::Vccpbd);
            }
        }
    }
}

/// The eight-lane kernel over runs of blocks (see [`apply_runs`]), its constants set up once.
/// The arrays' lengths are taken once: a run inside all of them is computed without
/// per-load bounds checks, any other with them.
fn runs_simd<const VC: bool>(inp: &ApplyInput<'_>, p: [&mut [f32]; 3], runs: impl Iterator<Item = Run>) {
    let [px, py, pz] = p;
    let c = Consts::new(inp);
    let (len_i, len_g) = (particle_len(inp, [&*px, &*py, &*pz]), sums_len(inp, VC));
    for (k, b, len) in runs {
        let inside = (b + len) * LANES <= len_i && (k + len) * LANES <= len_g;
        for l in 0..len {
            let (i, g) = ((b + l) * LANES, (k + l) * LANES);
            if inside {
                // SAFETY: `i + LANES <= (b + len) LANES <= len_i`, the shortest array indexed
                // by particle, and `g + LANES <= len_g`, the shortest indexed by sum.
                unsafe { lanes::<VC, false>(&c, inp, [&mut *px, &mut *py, &mut *pz], i, g) }
            } else {
                // SAFETY: the checked form reads and writes through bounds-checked loads.
                unsafe { lanes::<VC, true>(&c, inp, [&mut *px, &mut *py, &mut *pz], i, g) }
            }
        }
    }
}

/// The shortest of the arrays the kernel indexes by particle.
fn particle_len(inp: &ApplyInput<'_>, p: [&[f32]; 3]) -> usize {
    let v = inp.v.map_or(usize::MAX, shortest);
    shortest(inp.x).min(shortest(p)).min(inp.w.len()).min(v)
}

/// The shortest of the arrays the kernel indexes by sum (`vc`: the VcCPBD kernel's too).
fn sums_len(inp: &ApplyInput<'_>, vc: bool) -> usize {
    if !vc {
        return inp.sums.len();
    }
    let q = if inp.v.is_some() { usize::MAX } else { shortest(inp.q) };
    inp.sums.len().min(inp.b.len()).min(q)
}

/// The length of the shortest of three arrays.
fn shortest(a: [&[f32]; 3]) -> usize {
    a[0].len().min(a[1].len()).min(a[2].len())
}

/// The kernel's constants in lanes.
struct Consts {
    mu: F32s,
    h: F32s,
    r2: F32s,
}

impl Consts {
    #[inline(always)]
    fn new(inp: &ApplyInput<'_>) -> Self {
        Consts {
            mu: F32s::splat(inp.friction),
            h: F32s::splat(inp.h),
            r2: F32s::splat(inp.r * inp.r),
        }
    }
}

fn apply_simd<const VC: bool>(inp: &ApplyInput<'_>, p: [&mut [f32]; 3]) {
    let [px, py, pz] = p;
    let c = Consts::new(inp);
    for i in (0..px.len()).step_by(LANES) {
        // SAFETY: the checked form reads and writes through bounds-checked loads.
        unsafe { lanes::<VC, true>(&c, inp, [&mut *px, &mut *py, &mut *pz], i, inp.start + i) };
    }
}

/// One block of the kernel: particles `i..i + 8` of `x`, `w`, `p`; sums, box centres and
/// damping rates at `g..g + 8`; with bounds-checked loads and stores when `CHECKED`.
///
/// # Safety
/// Without `CHECKED`, `i + LANES` is at most the length of every array indexed by particle
/// (`x`, `w`, `p`, `v`) and `g + LANES` of every one indexed by sum (the sums, `q`, `b`).
#[inline(always)]
unsafe fn lanes<const VC: bool, const CHECKED: bool>(c: &Consts, inp: &ApplyInput<'_>, p: [&mut [f32]; 3], i: usize, g: usize) {
    let [px, py, pz] = p;
    // SAFETY (all unchecked loads and stores): the caller's guarantee above.
    let ld = |a: &[f32], at: usize| if CHECKED { load(a, at) } else { unsafe { load_unchecked(a, at) } };
    let ld3 = |a: [&[f32]; 3], at: usize| Vec3x8 {
        x: ld(a[0], at),
        y: ld(a[1], at),
        z: ld(a[2], at),
    };
    let st = |a: &mut [f32], v: F32s| {
        if CHECKED {
            store(a, i, v)
        } else {
            unsafe { store_unchecked(a, i, v) }
        }
    };
    let recs: &[Record; LANES] = if CHECKED {
        inp.sums[g..g + LANES].try_into().expect("eight records")
    } else {
        // SAFETY: `g + LANES <= inp.sums.len()` (the caller's guarantee); `[Record; LANES]` has
        // the alignment of `Record`.
        unsafe { &*inp.sums.as_ptr().add(g).cast::<[Record; LANES]>() }
    };
    let s = transpose_records(recs);
    let (zero, one) = (F32s::ZERO, F32s::ONE);
    let k = s[10];
    let active = k.simd_gt(zero) & ld(inp.w, i).simd_gt(zero);
    let inv = one / k.max(one);
    let x = ld3(inp.x, i);
    let p0 = ld3([&*px, &*py, &*pz], i);
    // The corrections over the approaching contacts when there are any ([`corrections`]).
    let (c0, appr) = (Vec3x8 { x: s[0], y: s[1], z: s[2] }, s[11]);
    let cs = Vec3x8::select(appr.simd_gt(zero), c0.scale(k / appr), c0);
    let f = Vec3x8 { x: s[3], y: s[4], z: s[5] };
    let disp = p0 - x;
    let mut t = p0 + cs.scale(inv * F32s::splat(RELAXATION)) + (f.scale(inv) - disp).scale(F32s::splat(0.5)).scale(c.mu);
    if VC {
        let n = Vec3x8 { x: s[6], y: s[7], z: s[8] };
        let nl = n.length_sq().sqrt();
        let nh = n.scale(one / nl.max(F32s::splat(f32::MIN_POSITIVE)));
        let e = s[9] * inv;
        let q = match inp.v {
            Some(v) => x + ld3(v, i).scale(c.h),
            None => ld3(inp.q, g),
        };
        let back = (t - q).length_sq().simd_ge(c.r2);
        let beta = (ld(inp.b, g) * c.h).min(one);
        let amt = beta * (t - x).dot(nh) + beta * beta * e * F32s::splat(0.25);
        let osc = t - nh.scale(amt);
        t = Vec3x8::select(back, q, osc);
    }
    let out = Vec3x8::select(active, t, p0);
    st(px, out.x);
    st(py, out.y);
    st(pz, out.z);
}

/// Scalar twin of the velocity-correction kernel.
fn apply_scalar(inp: &ApplyInput<'_>, p: [&mut [f32]; 3], vc: bool) {
    let [px, py, pz] = p;
    let (mu, h, r2) = (inp.friction, inp.h, inp.r * inp.r);
    for i in 0..px.len() {
        let g = inp.start + i;
        let s = &inp.sums[g];
        let k = s[10];
        if !(k > 0.0 && inp.w[i] > 0.0) {
            continue;
        }
        let inv = 1.0 / k.max(1.0);
        let relaxed = inv * RELAXATION;
        let x = [inp.x[0][i], inp.x[1][i], inp.x[2][i]];
        let p0 = [px[i], py[i], pz[i]];
        let c = corrections(s);
        let mut t = [0.0f32; 3];
        for a in 0..3 {
            let disp = p0[a] - x[a];
            t[a] = p0[a] + c[a] * relaxed + (s[3 + a] * inv - disp) * 0.5 * mu;
        }
        if vc {
            let n = [s[6], s[7], s[8]];
            let nl = dot(n, n).sqrt();
            let il = 1.0 / nl.max(f32::MIN_POSITIVE);
            let nh = n.map(|c| c * il);
            let e = s[9] * inv;
            let q = match inp.v {
                Some(v) => [x[0] + v[0][i] * h, x[1] + v[1][i] * h, x[2] + v[2][i] * h],
                None => [inp.q[0][g], inp.q[1][g], inp.q[2][g]],
            };
            let tq = [t[0] - q[0], t[1] - q[1], t[2] - q[2]];
            if dot(tq, tq) >= r2 {
                t = q;
            } else {
                let beta = (inp.b[g] * h).min(1.0);
                let tx = [t[0] - x[0], t[1] - x[1], t[2] - x[2]];
                let amt = beta * dot(tx, nh) + beta * beta * e * 0.25;
                t = [t[0] - nh[0] * amt, t[1] - nh[1] * amt, t[2] - nh[2] * amt];
            }
        }
        px[i] = t[0];
        py[i] = t[1];
        pz[i] = t[2];
    }
}

#[cfg(test)]
#[path = "response_tests.rs"]
pub(crate) mod tests;
