//! Per-particle obstacle kernels of the step: contact slots, the plane and sphere contact
//! generators in SIMD (`f32x8`) with scalar twins, the position projection (SIMD + scalar
//! twin), the response along the path and the velocity pass (scalar here, SIMD twins in
//! `obstacle_simd.rs`).
//!
//! **Slots.** Each obstacle owns one contact slot per particle: the tangent plane `(c, n)` of
//! [`ShapeContact`](crate::model::shapes::ShapeContact) (or of a mesh face), in blocks of eight
//! with a per-block "touched" flag ([`Slots`], `obstacle_slots.rs`). "No contact" is the zero
//! normal. `a` is the approach speed `max(0, -n.(v - u))` of the predicted velocity when the
//! contact was found ([`fill_approach`]). Every pass skips blocks whose flag is down; the
//! lane passes also skip, within a block, each obstacle whose flag is down (a cloth on the
//! floor beside a ball then pays for the floor only).
//!
//! **Pre-tests.** A block runs [`shape_may_touch_simd`] before a plane's or a sphere's
//! contacts; when it says no, the block gets no contact and its slots are not written (zeroed
//! once if they held one). For a plane the pre-test is the contact test itself, `n.(p - c) <
//! reach` in some lane (the same expression, so the same decision): a floor far below a cloth
//! costs one dot product a block instead of the block's seven stores and the checks that read
//! them back.
//!
//! **Sphere pre-test.** Most blocks of a large cloth are far from a sphere. Before the full
//! sphere test (three square roots, divisions) a block runs [`shape_may_touch_simd`]: the
//! proximity test itself (the same expression, so the same bits), and a distance bound for
//! the crossing. A path `x -> p` that enters the ball of radius `r + th <= R = r + reach` at
//! `e = x + t (p - x)`, `0 <= t <= 1`, ends within `|p - e| <= |p - x|` of it, so
//! `|p - c| <= R + |p - x|`. The crossing's `t` comes from a quadratic whose rounding error
//! near tangency is of order `sqrt(eps) ~ 3e-4` relative, so the bound is taken with a margin
//! of `2e-3` relative (and `1e-6` m): a lane is far when
//! `|p - c| (1 - 2e-3) > (R + |p - x|) (1 + 2e-3) + 1e-6`. A block whose lanes are all far
//! and not in proximity gets exactly the empty block the full test would write (or keeps it,
//! without a write); `sphere_pretest_never_rejects_a_contact` tests this on paths around the
//! proximity and thickness shells, grazing ones included.
//!
//! **Projection** (every solver iteration, after the constraints): the inequality
//! `n.(p - c) >= Th` is enforced by `p += max(0, Th - n.(p - c)) n` (PBD, Müller et al. 2007;
//! the paper's "stand off the face by the thickness"). A zero normal leaves `p` unchanged,
//! bit for bit (a signed zero too), so blocks without contact need not be visited.
//!
//! **Velocity pass** (after the velocity update): for a particle standing on its contact
//! plane (`n.(x - c) <= Th + TOUCH_SLACK`), the velocity relative to the obstacle `w = v - u`
//! loses its approaching normal part and Coulomb friction shrinks the tangential part `w_t` by
//! `mu max(a, -n.w)`: `w_t' = w_t max(0, 1 - mu max(a, -n.w) / |w_t|)`. After a position
//! projection the updated velocity has almost no normal part left, so the normal impulse is
//! measured before the projection, by the approach speed `a` (for cloth resting under gravity
//! `a = g h cos(theta)`, which gives Coulomb's `mu g cos(theta)` deceleration).
//!
//! SIMD and scalar kernels perform the same f32 operations in the same order, with no fused
//! multiply-add, so they agree bit for bit (`tests.rs`).

use crate::data::lanes::{F32s, Vec3x8, LANES};
use crate::model::shapes::{dot, sub, Shape};
use crate::obstacles::mesh::response::resolve_against_plane;

mod simd;
mod slots;
pub use simd::{resolve_simd, velocity_pass_simd};
pub(crate) use slots::skip_untouched;
pub(crate) use slots::SlotsPtr;
pub use slots::{
    block_nonzero, block_touched, normals_set, read_approach, read_slot, write_slot, SlotBlocks, Slots, SlotsView, SLOT_BLOCK,
};
/// A particle within this distance beyond the thickness still counts as touching.
pub const TOUCH_SLACK: f32 = 1e-4;

/// Sets the approach speeds `max(0, -n.(v - u))` of the eight slots of one block (`out`, the
/// block's floats) from the velocities of particles `b * 8 ..`; slots without contact get 0
/// (always `+0.0`: the maximum is a comparison and a choice, as in [`fill_approach_simd`]).
pub fn fill_approach(out: &mut [f32], b: usize, v: [&[f32]; 3], u: [f32; 3]) {
    if !normals_set(out) {
        out[6 * LANES..7 * LANES].fill(0.0);
        return;
    }
    for l in 0..LANES {
        let i = b * LANES + l;
        let n = [3, 4, 5].map(|k| out[k * LANES + l]);
        let rel = [v[0][i] - u[0], v[1][i] - u[1], v[2][i] - u[2]];
        let a = -dot(n, rel);
        out[6 * LANES + l] = if a > 0.0 { a } else { 0.0 };
    }
}

/// [`fill_approach`] eight lanes at once (bitwise equal to it).
pub fn fill_approach_simd(out: &mut [f32], b: usize, v: [&[f32]; 3], u: [f32; 3]) {
    let zero = F32s::splat(0.0);
    // A block without contact (most of a large cloth) need not read its velocities.
    if !normals_set(out) {
        out[6 * LANES..7 * LANES].fill(0.0);
        return;
    }
    let n = Vec3x8 {
        x: crate::data::lanes::load(out, 3 * LANES),
        y: crate::data::lanes::load(out, 4 * LANES),
        z: crate::data::lanes::load(out, 5 * LANES),
    };
    let rel = Vec3x8::load(v[0], v[1], v[2], b * LANES) - Vec3x8::splat(u);
    let a = -n.dot(rel);
    crate::data::lanes::store(out, 6 * LANES, a.simd_gt(zero).select(a, zero));
}

/// The velocity `w` (relative to the obstacle) after contact with normal `n`, approach speed
/// `a` and friction `mu` (module doc).
pub fn contact_velocity(w: [f32; 3], n: [f32; 3], a: f32, mu: f32) -> [f32; 3] {
    let wn = dot(w, n);
    let wt = [w[0] - wn * n[0], w[1] - wn * n[1], w[2] - wn * n[2]];
    // maxima as a comparison and a choice, as the SIMD twin does them
    let keep_n = if wn > 0.0 { wn } else { 0.0 };
    let lt = dot(wt, wt).sqrt();
    let drop = mu * if -wn > a { -wn } else { a };
    let f = if lt <= drop { 0.0 } else { 1.0 - drop / lt };
    [0, 1, 2].map(|k| wt[k] * f + keep_n * n[k])
}

/// Read-only particle data a generator needs, all padded arrays of the same length.
#[derive(Clone, Copy)]
pub struct GenInput<'a> {
    /// Start positions.
    pub x: [&'a [f32]; 3],
    /// Predicted positions.
    pub p: [&'a [f32]; 3],
    /// Inverse masses (0 = pinned: never collided).
    pub w: &'a [f32],
    /// Thickness per particle.
    pub th: &'a [f32],
    /// Contact reach per particle (`>= th`).
    pub reach: &'a [f32],
    /// Real particles (lanes at or beyond are padding).
    pub n: usize,
    /// The obstacle's displacement during this substep (start is shifted by `-shift`).
    pub shift: [f32; 3],
}

impl GenInput<'_> {
    /// Start (in the obstacle's end frame) and prediction of particle `i`.
    #[inline]
    pub fn path(&self, i: usize) -> ([f32; 3], [f32; 3]) {
        let x = [0, 1, 2].map(|k| self.x[k][i] - self.shift[k]);
        (x, [0, 1, 2].map(|k| self.p[k][i]))
    }
    /// Is particle `i` a real, movable particle?
    #[inline]
    pub fn live(&self, i: usize) -> bool {
        i < self.n && self.w[i] > 0.0
    }
}

/// Scalar twin of [`shape_block_simd`]: the contacts of the eight particles of block `b`.
pub fn shape_block_scalar(shape: &Shape, g: &GenInput, b: usize, out: &mut [f32]) {
    for l in 0..LANES {
        let i = b * LANES + l;
        let c = if g.live(i) {
            let (x, p) = g.path(i);
            shape.contact(x, p, g.th[i], g.reach[i])
        } else {
            None
        };
        let (pt, n) = c.map_or(([0.0; 3], [0.0; 3]), |c| (c.point, c.normal));
        write_slot(out, l, pt, n);
    }
}

/// Relative margin of the sphere pre-test's distance bound (module doc).
const PRETEST_REL: f32 = 2e-3;
/// Absolute margin of the sphere pre-test's distance bound, m.
const PRETEST_ABS: f32 = 1e-6;

/// May block `b` touch `shape`? Always for shapes other than a plane or a sphere; for those
/// the pre-tests of the module doc, eight lanes at once: `false` guarantees that
/// [`shape_block_simd`] (and its twin) finds no contact in the block.
pub fn shape_may_touch_simd(shape: &Shape, g: &GenInput, b: usize) -> bool {
    let i = b * LANES;
    let (center, radius) = match shape {
        Shape::Sphere { center, radius } => (center, radius),
        Shape::Plane { point, normal } => {
            let h = plane_heights(*point, *normal, Vec3x8::load(g.p[0], g.p[1], g.p[2], i));
            return h.simd_lt(crate::data::lanes::load(g.reach, i)).any();
        }
        _ => return true,
    };
    let c = Vec3x8::splat(*center);
    let p = Vec3x8::load(g.p[0], g.p[1], g.p[2], i);
    let x = Vec3x8::load(g.x[0], g.x[1], g.x[2], i) - Vec3x8::splat(g.shift);
    let rr = F32s::splat(*radius) + crate::data::lanes::load(g.reach, i);
    let l2 = (p - c).length_sq();
    let prox = l2.simd_lt(rr * rr);
    let dl = (p - x).length_sq().sqrt();
    let bound = (rr + dl) * F32s::splat(1.0 + PRETEST_REL) + F32s::splat(PRETEST_ABS);
    let far = (l2.sqrt() * F32s::splat(1.0 - PRETEST_REL)).simd_gt(bound);
    (prox | !far).any()
}

/// Scalar twin of [`shape_may_touch_simd`] (the same operations lane by lane).
pub fn shape_may_touch_scalar(shape: &Shape, g: &GenInput, b: usize) -> bool {
    let (center, radius) = match shape {
        Shape::Sphere { center, radius } => (center, radius),
        Shape::Plane { .. } => {
            return (b * LANES..(b + 1) * LANES).any(|i| shape.signed_distance(g.path(i).1) < g.reach[i]);
        }
        _ => return true,
    };
    (b * LANES..(b + 1) * LANES).any(|i| {
        let (x, p) = g.path(i);
        let rr = radius + g.reach[i];
        let dp = sub(p, *center);
        let l2 = dot(dp, dp);
        let prox = l2 < rr * rr;
        let d = sub(p, x);
        let dl = dot(d, d).sqrt();
        let bound = (rr + dl) * (1.0 + PRETEST_REL) + PRETEST_ABS;
        let far = l2.sqrt() * (1.0 - PRETEST_REL) > bound;
        prox || !far
    })
}

/// Contacts of block `b` with `shape`, eight lanes at once for planes and spheres (other
/// shapes use the scalar path). `out` is the block's 48 floats.
pub fn shape_block_simd(shape: &Shape, g: &GenInput, b: usize, out: &mut [f32]) {
    let i = b * LANES;
    let zero = F32s::splat(0.0);
    let live = if i + LANES <= g.n {
        crate::data::lanes::load(g.w, i).simd_gt(zero)
    } else {
        F32s::from(std::array::from_fn::<f32, LANES, _>(|l| if g.live(i + l) { 1.0 } else { 0.0 })).simd_gt(zero)
    };
    let p = Vec3x8::load(g.p[0], g.p[1], g.p[2], i);
    let reach = crate::data::lanes::load(g.reach, i);
    let (point, normal, hit) = match shape {
        Shape::Plane { point, normal } => {
            let n = Vec3x8::splat(*normal);
            let h = plane_heights(*point, *normal, p);
            let q = p + n.scale(-h);
            (q, n, h.simd_lt(reach))
        }
        Shape::Sphere { center, radius } => {
            let th = crate::data::lanes::load(g.th, i);
            let x = Vec3x8::load(g.x[0], g.x[1], g.x[2], i) - Vec3x8::splat(g.shift);
            sphere_lanes(*center, *radius, x, p, th, reach)
        }
        _ => return shape_block_scalar(shape, g, b, out),
    };
    let m = live & hit;
    for (k, v) in [point.x, point.y, point.z, normal.x, normal.y, normal.z, zero]
        .into_iter()
        .enumerate()
    {
        crate::data::lanes::store(out, k * LANES, m.select(v, zero));
    }
}

/// Heights `n.(p - c)` of eight predictions `p` above the plane through `point` with unit
/// `normal`: the plane's contact test and its pre-test compare them with the reach.
#[inline(always)]
fn plane_heights(point: [f32; 3], normal: [f32; 3], p: Vec3x8) -> F32s {
    Vec3x8::splat(normal).dot(p - Vec3x8::splat(point))
}

/// The sphere test of `shapes::ball_contact`, lane-wise: `(point, normal, hit)`.
///
/// The scalar test normalises one vector a particle: `p - c` in proximity (or `x - c` when
/// `p = c`), else the entry point's `e - c`. The lanes choose that vector and its squared
/// length first and then take one square root and one normalisation (the scalar's
/// operations on the chosen values, so the same bits), instead of three normalisations of
/// which two are thrown away: the divider bounds this kernel.
#[inline(always)]
fn sphere_lanes(center: [f32; 3], r: f32, x: Vec3x8, p: Vec3x8, th: F32s, reach: F32s) -> (Vec3x8, Vec3x8, F32s) {
    let zero = F32s::splat(0.0);
    let one = F32s::splat(1.0);
    let c = Vec3x8::splat(center);
    let rv = F32s::splat(r);
    let up = Vec3x8::splat([0.0, 1.0, 0.0]);
    // proximity
    let dp = p - c;
    let l2 = dp.length_sq();
    let rr = rv + reach;
    let prox = l2.simd_lt(rr * rr);
    let dx = x - c;
    // crossing into the ball of radius r + th
    let d = p - x;
    let f = dx;
    let a = d.length_sq();
    let b = f.dot(d);
    let rt = rv + th;
    let cc = f.length_sq() - rt * rt;
    let disc = b * b - a * cc;
    let t = (-b - disc.sqrt()) / a;
    let cross = a.simd_gt(zero) & cc.simd_gt(zero) & b.simd_lt(zero) & disc.simd_ge(zero) & t.simd_ge(zero) & t.simd_le(one);
    let e = (x + d.scale(t)) - c;
    // the one vector each lane normalises; `p = c` exactly (l2 = 0) falls back to `x - c`
    let at_centre = prox & !l2.simd_gt(zero);
    let v = Vec3x8::select(prox, Vec3x8::select(at_centre, dx, dp), e);
    let len = v.length_sq().sqrt();
    let n = Vec3x8::select(len.simd_gt(zero), v / len, up);
    (c + n.scale(rv), n, prox | cross)
}

/// Scalar twin of [`project_simd`]: `p += max(0, Th - n.(p - c)) n` for every slot set, in
/// obstacle order, over the particles `start .. start + p[0].len()`; particles without any
/// contact keep their bits.
pub fn project_scalar<S: SlotBlocks>(slots: &[S], th: &[f32], start: usize, p: [&mut [f32]; 3]) {
    let [px, py, pz] = p;
    let mut i = 0;
    while i < px.len() {
        i = skip_untouched(slots, start, px.len(), i);
        if i >= px.len() {
            break;
        }
        let g = start + i;
        let mut q = [px[i], py[i], pz[i]];
        for s in slots {
            let (c, n) = read_slot(s.data(), g);
            if n == [0.0; 3] {
                continue;
            }
            let d = (th[g] - dot(n, sub(q, c))).max(0.0);
            q = [q[0] + n[0] * d, q[1] + n[1] * d, q[2] + n[2] * d];
        }
        (px[i], py[i], pz[i]) = (q[0], q[1], q[2]);
        i += 1;
    }
}

/// The projection eight particles at a time (`start` and the chunk length are multiples of
/// eight); blocks without contact are skipped, lanes without contact keep their bits.
pub fn project_simd<S: SlotBlocks>(slots: &[S], th: &[f32], start: usize, p: [&mut [f32]; 3]) {
    let [px, py, pz] = p;
    let zero = F32s::splat(0.0);
    for j in (0..px.len()).step_by(LANES) {
        let g = start + j;
        let b = g / LANES;
        if !block_touched(slots, b) {
            continue;
        }
        let mut q = Vec3x8::load(px, py, pz, j);
        let t = crate::data::lanes::load(th, g);
        for s in slots {
            let Some((c, n, set)) = simd::slot_lanes(s, b) else { continue };
            let d = (t - n.dot(q - c)).max(zero);
            q = Vec3x8::select(set, q + n.scale(d), q);
        }
        q.store(px, py, pz, j);
    }
}

/// The paper's response, applied once right after the contacts are found: for every obstacle's
/// contact in order, move `p` back along its path (in the obstacle's frame, start `x - shift`)
/// to the point that stands `Th` off the contact plane, or, when the path offers no such
/// point (the particle started inside the layer), back to its start if the path crossed a
/// mesh's plane (`mesh[k]` for obstacle `k`: a push along one face's normal can enter a
/// non-convex mesh through a neighbouring face), else push it along the normal. The chosen
/// contact is the first crossing of the path, so the point reached lies before every crossing:
/// outside the obstacle (`resolve_against_plane`, which [`resolve_position`](crate::obstacles::mesh::response::resolve_position) uses too).
/// Element-wise; the parallel and serial runs give the same bits.
pub fn resolve_along_path<S: SlotBlocks>(
    slots: &[S],
    shifts: &[[f32; 3]],
    mesh: &[bool],
    th: &[f32],
    start: usize,
    x: [&[f32]; 3],
    p: [&mut [f32]; 3],
) {
    let [px, py, pz] = p;
    let mut i = 0;
    while i < px.len() {
        i = skip_untouched(slots, start, px.len(), i);
        if i >= px.len() {
            break;
        }
        let g = start + i;
        let mut q = [px[i], py[i], pz[i]];
        for ((s, u), &mesh) in slots.iter().zip(shifts).zip(mesh) {
            let (c, n) = read_slot(s.data(), g);
            if n == [0.0; 3] {
                continue;
            }
            let xr = [x[0][i] - u[0], x[1][i] - u[1], x[2][i] - u[2]];
            q = resolve_against_plane(xr, q, c, n, th[g], mesh);
        }
        (px[i], py[i], pz[i]) = (q[0], q[1], q[2]);
        i += 1;
    }
}

/// Velocity pass for particles `start .. start + v[0].len()`: for every obstacle `k` whose
/// slot touches the particle, `v = u_k + contact_velocity(v - u_k, n, a, mu_k)`.
pub fn velocity_pass<S: SlotBlocks>(slots: &[S], motion: &[([f32; 3], f32)], th: &[f32], start: usize, x: [&[f32]; 3], v: [&mut [f32]; 3]) {
    let [vx, vy, vz] = v;
    let mut i = 0;
    while i < vx.len() {
        i = skip_untouched(slots, start, vx.len(), i);
        if i >= vx.len() {
            break;
        }
        let g = start + i;
        let q = [x[0][i], x[1][i], x[2][i]];
        for (s, &(u, mu)) in slots.iter().zip(motion) {
            let (c, n) = read_slot(s.data(), g);
            if n == [0.0; 3] || dot(n, sub(q, c)) > th[g] + TOUCH_SLACK {
                continue;
            }
            let rel = [vx[i] - u[0], vy[i] - u[1], vz[i] - u[2]];
            let w = contact_velocity(rel, n, read_approach(s.data(), g), mu);
            (vx[i], vy[i], vz[i]) = (w[0] + u[0], w[1] + u[1], w[2] + u[2]);
        }
        i += 1;
    }
}

#[cfg(test)]
mod tests;
