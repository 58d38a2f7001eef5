use super::*;
use crate::data::particles::Particles;
use crate::model::self_collision::Response;
use proptest::prelude::*;

/// xorshift in [-1, 1).
fn rng(seed: u64) -> impl FnMut() -> f32 {
    crate::test_rng::signed(seed | 1)
}

pub(crate) fn cloud(n: usize, seed: u64) -> Particles {
    let mut p = Particles::new();
    let mut r = rng(seed);
    for i in 0..n {
        let w = if i % 7 == 0 { 0.0 } else { 1.0 + r().abs() * 10.0 };
        p.push([r(), r(), r()], [r() * 5.0, r() * 5.0, r() * 5.0], w);
    }
    for i in 0..p.padded_len() {
        p.px[i] = p.x[i] + 0.01 * r();
        p.py[i] = p.y[i] + 0.01 * r();
        p.pz[i] = p.z[i] + 0.01 * r();
    }
    p
}

/// Random records of `len` particles: 0 to 3 contacts (some particles none), some of them
/// approaching (the movement-speed rescaling), some zero normals.
fn sums(len: usize, seed: u64) -> Vec<Record> {
    let mut r = rng(seed ^ 0x9e37);
    let mut s = vec![[0.0f32; RECORD]; len];
    for (i, rec) in s.iter_mut().enumerate() {
        let k = ((r() + 1.0) * 2.0) as u32; // 0..=3 contacts, some zero
        if k == 0 {
            continue;
        }
        rec[10] = k as f32;
        rec[11] = (((r() + 1.0) * 0.5 * (k + 1) as f32) as u32).min(k) as f32;
        for a in 0..3 {
            rec[a] = 0.005 * r();
            rec[3 + a] = 0.01 * r();
            rec[6 + a] = if i % 11 == 0 { 0.0 } else { r() };
        }
        rec[9] = -0.004 * (r() + 1.0);
    }
    s
}

pub(crate) fn bits(p: &Particles) -> Vec<u32> {
    [&p.x, &p.y, &p.z, &p.px, &p.py, &p.pz, &p.vx, &p.vy, &p.vz]
        .iter()
        .flat_map(|a| a.iter().map(|f| f.to_bits()))
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// The velocity-correction kernel: SIMD (serial and parallel chunks) == scalar twin,
    /// bitwise, in both modes, for lengths around the lane width and the chunk size.
    #[test]
    fn apply_simd_matches_scalar(n in prop_oneof![0usize..40, 4090usize..4110], seed in any::<u64>(),
            h_milli in 1u32..60, friction_pct in 0u32..=100, r_milli in 1u32..20, vc in any::<bool>()) {
        let base = cloud(n, seed);
        let len = base.padded_len();
        let s = sums(len, seed);
        let mut rb = rng(seed ^ 77);
        let b: Vec<f32> = (0..len).map(|_| (rb() + 1.0) * 20.0).collect();
        let q: Vec<Vec<f32>> = [&base.px, &base.py, &base.pz].iter().map(|a| a.iter().map(|v| v + 0.003 * rb()).collect()).collect();
        let mode = if vc { Response::Vccpbd } else { Response::Pbd };
        let h = h_milli as f32 * 1e-3;
        let run = |simd: bool, par: bool| {
            let mut p = base.clone();
            p.for_chunks(par, |c| {
                let inp = ApplyInput { start: c.start, x: [&*c.x, &*c.y, &*c.z], w: c.w, q: [&q[0], &q[1], &q[2]], v: None, b: &b, sums: &s,
                    friction: friction_pct as f32 / 100.0, h, r: r_milli as f32 * 1e-3 };
                apply(&inp, [c.px, c.py, c.pz], mode, simd);
            });
            bits(&p)
        };
        let reference = run(false, false);
        prop_assert_eq!(&reference, &run(true, false));
        prop_assert_eq!(&reference, &run(true, true));
        prop_assert_eq!(&reference, &run(false, true));
    }
}

/// Box centres derived from the velocities (`x + h v`, as predict and the clamp compute the
/// predictions) give the bits of the centres read from a copy, SIMD and scalar, in chunks
/// and in runs; the box test sends some particles back to their centre.
#[test]
fn derived_box_centres_equal_the_copied_ones() {
    let h = 0.01f32;
    let mut base = cloud(300, 9);
    for i in 0..base.padded_len() {
        base.px[i] = base.x[i] + base.vx[i] * h;
        base.py[i] = base.y[i] + base.vy[i] * h;
        base.pz[i] = base.z[i] + base.vz[i] * h;
    }
    let len = base.padded_len();
    let s = sums(len, 9);
    let b = vec![30.0; len];
    let q = [base.px.clone(), base.py.clone(), base.pz.clone()];
    let run = |derive: bool, simd: bool, runs: bool| {
        let mut p = base.clone();
        let v = [base.vx.clone(), base.vy.clone(), base.vz.clone()];
        let inp = |x, w, v, start| centres_input(x, w, derive.then_some(v), &q, &b, &s, start, h);
        if runs {
            let xs = [&base.x[..], &base.y[..], &base.z[..]];
            let blocks = len / crate::data::lanes::LANES;
            let runs = [(0, 0, 3), (3, 3, blocks - 3)].into_iter();
            let i = inp(xs, &base.w[..], [&v[0][..], &v[1][..], &v[2][..]], 0);
            super::apply_runs(&i, [&mut p.px[..], &mut p.py[..], &mut p.pz[..]], runs, Response::Vccpbd, simd);
        } else {
            p.for_chunks(false, |c| {
                let g = c.start..c.start + c.x.len();
                let vs = [&v[0][g.clone()], &v[1][g.clone()], &v[2][g]];
                let i = centres_input([&*c.x, &*c.y, &*c.z], c.w, derive.then_some(vs), &q, &b, &s, c.start, h);
                apply(&i, [c.px, c.py, c.pz], Response::Vccpbd, simd);
            });
        }
        p
    };
    let want = run(false, false, false);
    let back = (0..300)
        .filter(|&i| base.w[i] > 0.0 && s[i][10] > 0.0 && want.px[i].to_bits() == q[0][i].to_bits())
        .count();
    assert!(back > 10, "{back} particles sent back to their box centre");
    for (derive, simd, runs) in [
        (true, false, false),
        (true, true, false),
        (true, false, true),
        (true, true, true),
        (false, true, true),
    ] {
        assert_eq!(
            bits(&run(derive, simd, runs)),
            bits(&want),
            "derive {derive}, simd {simd}, runs {runs}"
        );
    }
}

/// The kernel's input of [`derived_box_centres_equal_the_copied_ones`].
#[allow(clippy::too_many_arguments)]
fn centres_input<'a>(
    x: [&'a [f32]; 3],
    w: &'a [f32],
    v: Option<[&'a [f32]; 3]>,
    q: &'a [Vec<f32>; 3],
    b: &'a [f32],
    sums: &'a [Record],
    start: usize,
    h: f32,
) -> ApplyInput<'a> {
    ApplyInput {
        start,
        x,
        w,
        q: [&q[0], &q[1], &q[2]],
        v,
        b,
        sums,
        friction: 0.3,
        h,
        r: 0.002,
    }
}

#[test]
fn apply_leaves_pinned_and_contactless_particles_alone() {
    let base = cloud(20, 5);
    let len = base.padded_len();
    let mut s = sums(len, 5);
    s[3][10] = 0.0;
    let b = vec![0.8; len];
    let mut p = base.clone();
    p.for_chunks(false, |c| {
        let inp = ApplyInput {
            start: c.start,
            x: [&*c.x, &*c.y, &*c.z],
            w: c.w,
            q: [&base.px, &base.py, &base.pz],
            v: None,
            b: &b,
            sums: &s,
            friction: 0.3,
            h: 0.01,
            r: 0.01,
        };
        apply(&inp, [c.px, c.py, c.pz], Response::Vccpbd, true);
    });
    for i in [0, 3, 7, 14] {
        assert_eq!(p.px[i].to_bits(), base.px[i].to_bits(), "particle {i}");
    }
}

#[test]
fn vccpbd_puts_a_far_moved_particle_back_to_its_box_centre() {
    let mut p = Particles::new();
    p.push([0.0; 3], [0.0; 3], 1.0);
    p.px[0] = 0.0;
    let len = p.padded_len();
    let mut s = vec![[0.0f32; RECORD]; len];
    s[0][10] = 1.0;
    s[0][0] = 0.5; // a correction far larger than the box radius
    s[0][6] = 1.0;
    s[0][9] = -0.001;
    let q = [vec![0.25; len], vec![0.0; len], vec![0.0; len]];
    let b = vec![0.8; len];
    p.for_chunks(false, |c| {
        let inp = ApplyInput {
            start: c.start,
            x: [&*c.x, &*c.y, &*c.z],
            w: c.w,
            q: [&q[0], &q[1], &q[2]],
            v: None,
            b: &b,
            sums: &s,
            friction: 0.0,
            h: 0.01,
            r: 0.01,
        };
        apply(&inp, [c.px, c.py, c.pz], Response::Vccpbd, false);
    });
    assert_eq!(p.px[0], 0.25);
}
