//! SIMD predict/update kernels and their scalar twins.

use crate::data::lanes::{load, store, F32s, Vec3x8, LANES};
use crate::data::particles::ParticleChunk;

/// What the predict kernel adds to velocities.
#[derive(Clone, Copy, Debug, Default)]
pub struct PredictParams<'a> {
    /// Substep length, s.
    pub h: f32,
    /// Gravity, m/s², if named.
    pub gravity: Option<[f32; 3]>,
    /// Linear drag coefficient, kg/s, if named.
    pub drag: Option<f32>,
    /// Per-particle external force arrays (x, y, z), N, if any effect produced forces.
    pub force: Option<[&'a [f32]; 3]>,
}

/// Predict on one chunk: SIMD when `simd`, else the scalar twin.
pub fn predict(c: ParticleChunk<'_>, p: &PredictParams<'_>, simd: bool) {
    predict_saving(c, None, p, simd);
}

/// [`predict`], also copying the chunk's state before it changes it into `saved` when given
/// (`x, y, z, vx, vy, vz`, six arrays of the chunk's length: the guard's backup), from the
/// values the kernel loads anyway: the same bits as
/// [`save_state`](ParticleChunk::save_state) and then [`predict`].
pub fn predict_saving(c: ParticleChunk<'_>, saved: Option<[&mut [f32]; 6]>, p: &PredictParams<'_>, simd: bool) {
    if let Some(s) = &saved {
        assert!(s.iter().all(|a| a.len() == c.x.len()), "one saved value a particle");
    }
    match (p.gravity.is_some(), p.drag.is_some(), p.force.is_some(), simd) {
        (false, false, false, true) => predict_simd::<false, false, false>(c, saved, p),
        (true, false, false, true) => predict_simd::<true, false, false>(c, saved, p),
        (false, true, false, true) => predict_simd::<false, true, false>(c, saved, p),
        (true, true, false, true) => predict_simd::<true, true, false>(c, saved, p),
        (false, false, true, true) => predict_simd::<false, false, true>(c, saved, p),
        (true, false, true, true) => predict_simd::<true, false, true>(c, saved, p),
        (false, true, true, true) => predict_simd::<false, true, true>(c, saved, p),
        (true, true, true, true) => predict_simd::<true, true, true>(c, saved, p),
        (g, d, f, false) => predict_scalar(c, saved, p, g, d, f),
    }
}

fn predict_simd<const G: bool, const D: bool, const F: bool>(
    c: ParticleChunk<'_>,
    mut saved: Option<[&mut [f32]; 6]>,
    p: &PredictParams<'_>,
) {
    let h = F32s::splat(p.h);
    let zero = F32s::ZERO;
    let one = F32s::ONE;
    let g = Vec3x8::splat(p.gravity.unwrap_or([0.0; 3]));
    let hc = F32s::splat(p.h * p.drag.unwrap_or(0.0));
    let empty: [&[f32]; 3] = [&[], &[], &[]];
    let f = p.force.unwrap_or(empty);
    if G {
        crate::model::effects::probe::enter(crate::model::effects::probe::GRAVITY);
    }
    if D {
        crate::model::effects::probe::enter(crate::model::effects::probe::DRAG);
    }
    for i in (0..c.x.len()).step_by(LANES) {
        let w = load(c.w, i);
        let mut v = Vec3x8::load(c.vx, c.vy, c.vz, i);
        let x = Vec3x8::load(c.x, c.y, c.z, i);
        if let Some([sx, sy, sz, svx, svy, svz]) = &mut saved {
            x.store(sx, sy, sz, i);
            v.store(svx, svy, svz, i);
        }
        if G {
            let free = w.simd_gt(zero);
            let gm = Vec3x8::select(free, g, Vec3x8::splat([0.0; 3]));
            v = v + gm.scale(h);
        }
        if F {
            let j = c.start + i;
            let fv = Vec3x8::load(f[0], f[1], f[2], j);
            v = v + fv.scale(w * h);
        }
        if D {
            v = v.scale(one / (one + hc * w));
        }
        let pp = x + v.scale(h);
        v.store(c.vx, c.vy, c.vz, i);
        pp.store(c.px, c.py, c.pz, i);
    }
}

/// Scalar twin of the predict kernel.
fn predict_scalar(c: ParticleChunk<'_>, saved: Option<[&mut [f32]; 6]>, p: &PredictParams<'_>, has_g: bool, has_d: bool, has_f: bool) {
    if let Some(saved) = saved {
        c.save_state(saved);
    }
    let h = p.h;
    let g = p.gravity.unwrap_or([0.0; 3]);
    let hc = p.h * p.drag.unwrap_or(0.0);
    let force = p.force.filter(|_| has_f);
    if has_g {
        crate::model::effects::probe::enter(crate::model::effects::probe::GRAVITY);
    }
    if has_d {
        crate::model::effects::probe::enter(crate::model::effects::probe::DRAG);
    }
    for i in 0..c.x.len() {
        let w = c.w[i];
        let (mut vx, mut vy, mut vz) = (c.vx[i], c.vy[i], c.vz[i]);
        if has_g {
            let gm = if w > 0.0 { g } else { [0.0; 3] };
            vx += gm[0] * h;
            vy += gm[1] * h;
            vz += gm[2] * h;
        }
        if let Some(f) = force {
            let j = c.start + i;
            let wh = w * h;
            vx += f[0][j] * wh;
            vy += f[1][j] * wh;
            vz += f[2][j] * wh;
        }
        if has_d {
            let k = 1.0 / (1.0 + hc * w);
            vx *= k;
            vy *= k;
            vz *= k;
        }
        c.px[i] = c.x[i] + vx * h;
        c.py[i] = c.y[i] + vy * h;
        c.pz[i] = c.z[i] + vz * h;
        c.vx[i] = vx;
        c.vy[i] = vy;
        c.vz[i] = vz;
    }
}

/// Update on one chunk: `v = (p - x) / h` (times the damping factor if given), `x = p`.
/// `damp` is indexed by global particle index.
pub fn update(c: ParticleChunk<'_>, h: f32, damp: Option<&[f32]>, simd: bool) {
    match (damp, simd) {
        (None, true) => update_simd::<false>(c, h, &[]),
        (Some(d), true) => update_simd::<true>(c, h, d),
        (d, false) => update_scalar(c, h, d),
    }
}

fn update_simd<const DAMP: bool>(c: ParticleChunk<'_>, h: f32, damp: &[f32]) {
    let inv_h = F32s::splat(1.0 / h);
    for i in (0..c.x.len()).step_by(LANES) {
        let x = Vec3x8::load(c.x, c.y, c.z, i);
        let p = Vec3x8::load(c.px, c.py, c.pz, i);
        let mut v = (p - x).scale(inv_h);
        if DAMP {
            v = v.scale(load(damp, c.start + i));
        }
        v.store(c.vx, c.vy, c.vz, i);
        store(c.x, i, p.x);
        store(c.y, i, p.y);
        store(c.z, i, p.z);
    }
}

/// Scalar twin of the update kernel.
fn update_scalar(c: ParticleChunk<'_>, h: f32, damp: Option<&[f32]>) {
    let inv_h = 1.0 / h;
    for i in 0..c.x.len() {
        let mut vx = (c.px[i] - c.x[i]) * inv_h;
        let mut vy = (c.py[i] - c.y[i]) * inv_h;
        let mut vz = (c.pz[i] - c.z[i]) * inv_h;
        if let Some(d) = damp {
            let k = d[c.start + i];
            vx *= k;
            vy *= k;
            vz *= k;
        }
        c.vx[i] = vx;
        c.vy[i] = vy;
        c.vz[i] = vz;
        c.x[i] = c.px[i];
        c.y[i] = c.py[i];
        c.z[i] = c.pz[i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::particles::Particles;
    use proptest::prelude::*;

    fn cloud(n: usize, seed: u64) -> Particles {
        let mut p = Particles::new();
        let mut r = crate::test_rng::signed(seed | 1);
        for i in 0..n {
            let w = if i % 7 == 0 { 0.0 } else { 1.0 + r().abs() * 100.0 };
            p.push([r(), r(), r()], [r(), r(), r()], w);
        }
        p
    }

    fn bits(p: &Particles) -> Vec<u32> {
        [&p.x, &p.y, &p.z, &p.px, &p.py, &p.pz, &p.vx, &p.vy, &p.vz]
            .iter()
            .flat_map(|a| a.iter().map(|f| f.to_bits()))
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// SIMD (serial and in parallel chunks) == scalar twin, bitwise, for every effect set,
        /// lengths around the lane width and the chunk size.
        #[test]
        fn predict_update_simd_matches_scalar(n in prop_oneof![0usize..40, 4090usize..4110, 9000usize..9100], seed in any::<u64>(),
                h in 1e-4f32..0.1, g in any::<bool>(), d in any::<bool>(), f in any::<bool>(), damp in any::<bool>()) {
            let base = cloud(n, seed);
            let len = base.padded_len();
            let fx: Vec<f32> = (0..len).map(|i| (i as f32).sin()).collect();
            let fy: Vec<f32> = (0..len).map(|i| (i as f32).cos()).collect();
            let fz: Vec<f32> = (0..len).map(|i| (i as f32 * 0.5).sin()).collect();
            let dk: Vec<f32> = (0..len).map(|i| 1.0 / (1.0 + (i % 5) as f32 * h)).collect();
            let params = PredictParams { h, gravity: g.then_some([0.1, -9.81, 0.3]), drag: d.then_some(0.7), force: f.then_some([&fx[..], &fy[..], &fz[..]]) };
            let damp = damp.then_some(&dk[..]);
            let run = |simd: bool, par: bool| {
                let mut p = base.clone();
                p.for_chunks(par, |c| predict(c, &params, simd));
                // Perturb predictions as a solver would, identically for all runs.
                for i in 0..p.padded_len() { p.px[i] += 1e-3 * (i as f32 * 0.1).sin(); }
                p.for_chunks(par, |c| update(c, h, damp, simd));
                bits(&p)
            };
            let s = run(false, false);
            prop_assert_eq!(&s, &run(true, false));
            prop_assert_eq!(&s, &run(true, true));
            prop_assert_eq!(&s, &run(false, true));
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]
        /// Predict with the guard's copy, SIMD and scalar, serial and in parallel chunks: the
        /// copy holds the state before the step and the particles the bits of predict alone.
        #[test]
        fn predict_saving_copies_the_state_before_and_predicts_alike(n in prop_oneof![0usize..40, 4090usize..4110], seed in any::<u64>(),
                h in 1e-4f32..0.1, g in any::<bool>(), d in any::<bool>()) {
            let base = cloud(n, seed);
            let params = PredictParams { h, gravity: g.then_some([0.1, -9.81, 0.3]), drag: d.then_some(0.7), force: None };
            let want = {
                let mut p = base.clone();
                p.for_chunks(false, |c| predict(c, &params, false));
                bits(&p)
            };
            let before: Vec<Vec<u32>> = [&base.x, &base.y, &base.z, &base.vx, &base.vy, &base.vz]
                .iter()
                .map(|a| a.iter().map(|f| f.to_bits()).collect())
                .collect();
            for (simd, par) in [(false, false), (true, false), (true, true), (false, true)] {
                let mut p = base.clone();
                let mut saved: [Vec<f32>; 6] = Default::default();
                p.for_chunks_saving(par, &mut saved, |c, s| predict_saving(c, Some(s), &params, simd));
                prop_assert_eq!(&bits(&p), &want);
                let got: Vec<Vec<u32>> = saved.iter().map(|a| a.iter().map(|f| f.to_bits()).collect()).collect();
                prop_assert_eq!(&got, &before);
            }
        }
    }

    #[test]
    fn pinned_particles_ignore_gravity() {
        let mut p = Particles::new();
        p.push([0.0; 3], [0.0; 3], 0.0);
        p.push([0.0; 3], [0.0; 3], 1.0);
        let params = PredictParams {
            h: 0.1,
            gravity: Some([0.0, -10.0, 0.0]),
            ..Default::default()
        };
        p.for_chunks(false, |c| predict(c, &params, true));
        assert_eq!(p.vy[0], 0.0);
        assert!((p.vy[1] + 1.0).abs() < 1e-6);
        assert!((p.py[1] + 0.1).abs() < 1e-6);
    }
}
