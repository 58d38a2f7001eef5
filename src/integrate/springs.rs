//! Spring forces of the mass-spring model: the SIMD/parallel kernel and its scalar twin.
//!
//! Every distance constraint `(a, b, rest, α)` is read as a Hooke spring of stiffness
//! `k = 1/α` (or the solver's [`stiffness`](crate::SolverParams::stiffness) when `α = 0`):
//!
//! ```text
//! d = x_b - x_a,  l = |d|,  f_a += k (l - rest) d / l,  f_b -= k (l - rest) d / l
//! ```
//!
//! so the spring stores the energy `½ k (l - rest)²`, the same energy a compliant XPBD constraint
//! stores (`C² / 2α`, Macklin et al. 2016 eq. 3). The kernel walks the constraint colours of
//! [`DistanceSet`]: no particle appears twice in a colour, so a colour's springs can add into
//! the force arrays in parallel chunks, eight at a time, and the colour order fixes the order of
//! every particle's additions. The SIMD kernel and the scalar twin do the same operations in the
//! same order without FMA, so they agree bit for bit on any number of threads.

use rayon::prelude::*;

use crate::constraints::distance::{DistanceSet, CHUNK, MIN_LENGTH};
use crate::data::lanes::{load, load_idx, F32s, SharedVec3, LANES};

/// Stiffness of one spring: `1/α`, or `stiffness` when `α = 0`.
#[inline(always)]
pub fn spring_stiffness(compliance: f32, stiffness: f32) -> f32 {
    if compliance > 0.0 {
        1.0 / compliance
    } else {
        stiffness
    }
}

/// Adds every spring's force at positions `x` into `f` (SIMD; each colour in parallel chunks
/// when `parallel`, on the current rayon pool). `f` must be as long as the padded particle
/// arrays; it is not cleared.
pub fn add_spring_forces_simd(set: &DistanceSet, x: [&[f32]; 3], f: [&mut [f32]; 3], stiffness: f32, parallel: bool) {
    let [fx, fy, fz] = f;
    let out = SharedVec3::new(fx, fy, fz);
    for col in &set.colours {
        let run = |k0: usize, k1: usize| {
            // SAFETY: within one colour no particle repeats (the sink only in padding, where the
            // force is zero), so no two tasks touch the same force element.
            unsafe {
                springs_block_simd(
                    &col.a[k0..k1],
                    &col.b[k0..k1],
                    &col.rest[k0..k1],
                    &col.compliance[k0..k1],
                    x,
                    &out,
                    stiffness,
                )
            }
        };
        let n = col.a.len();
        if parallel && n > CHUNK {
            (0..n.div_ceil(CHUNK))
                .into_par_iter()
                .for_each(|c| run(c * CHUNK, ((c + 1) * CHUNK).min(n)));
        } else {
            run(0, n);
        }
    }
}

/// # Safety
/// No other thread may touch the force elements of the particles in `a` and `b`.
#[inline]
unsafe fn springs_block_simd(a: &[u32], b: &[u32], rest: &[f32], comp: &[f32], x: [&[f32]; 3], out: &SharedVec3, stiffness: f32) {
    let zero = F32s::ZERO;
    let one = F32s::ONE;
    let min_len = F32s::splat(MIN_LENGTH);
    let kdef = F32s::splat(stiffness);
    for i in (0..a.len()).step_by(LANES) {
        let ia = load_idx(a, i);
        let ib = load_idx(b, i);
        let g = |s: &[f32], idx: &[u32; LANES]| crate::data::lanes::gather1(s, idx);
        let d = crate::data::lanes::Vec3x8 {
            x: g(x[0], &ib) - g(x[0], &ia),
            y: g(x[1], &ib) - g(x[1], &ia),
            z: g(x[2], &ib) - g(x[2], &ia),
        };
        let len = d.length_sq().sqrt();
        let c = load(comp, i);
        let soft = c.simd_gt(zero);
        // 1/α where α > 0; the division by 1 elsewhere keeps the lanes finite.

        let k = soft.select(one / soft.select(c, one), kdef);
        let valid = len.simd_gt(min_len);
        let s = valid.select(k * (len - load(rest, i)) / len, zero);
        let fd = d.scale(s);
        // SAFETY: indices are below the padded length and exclusive to this task (caller).
        unsafe {
            let fa = out.gather(&ia) + fd;
            out.scatter(&ia, fa);
            let fb = out.gather(&ib) - fd;
            out.scatter(&ib, fb);
        }
    }
}

/// The scalar twin of [`add_spring_forces_simd`]: one spring at a time, one thread.
pub fn add_spring_forces_scalar(set: &DistanceSet, x: [&[f32]; 3], f: [&mut [f32]; 3], stiffness: f32) {
    let [fx, fy, fz] = f;
    for col in &set.colours {
        for k in 0..col.a.len() {
            let (a, b) = (col.a[k] as usize, col.b[k] as usize);
            let (dx, dy, dz) = (x[0][b] - x[0][a], x[1][b] - x[1][a], x[2][b] - x[2][a]);
            let len = (dx * dx + dy * dy + dz * dz).sqrt();
            let c = col.compliance[k];
            let ks = if c > 0.0 { 1.0 / c } else { stiffness };
            let s = if len > MIN_LENGTH { ks * (len - col.rest[k]) / len } else { 0.0 };
            let (gx, gy, gz) = (dx * s, dy * s, dz * s);
            fx[a] += gx;
            fy[a] += gy;
            fz[a] += gz;
            fx[b] -= gx;
            fy[b] -= gy;
            fz[b] -= gz;
        }
    }
}

/// Energy stored in the springs at positions `x`, J (`Σ ½ k (l - rest)²`, f64 sums, serial).
pub fn spring_energy(set: &DistanceSet, x: [&[f32]; 3], stiffness: f32) -> f64 {
    let mut e = 0.0;
    for col in &set.colours {
        for k in 0..col.real {
            let (a, b) = (col.a[k] as usize, col.b[k] as usize);
            let d: [f64; 3] = std::array::from_fn(|j| x[j][b] as f64 - x[j][a] as f64);
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let ks = spring_stiffness(col.compliance[k], stiffness) as f64;
            e += 0.5 * ks * (l - col.rest[k] as f64).powi(2);
        }
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::distance::DistanceInput;
    use crate::data::lanes::round_up;
    use proptest::prelude::*;

    fn setup(n: usize, m: usize, seed: u64) -> (DistanceSet, [Vec<f32>; 3]) {
        let mut rnd = crate::test_rng::unit(seed | 1);
        let len = round_up(n + 1);
        let mut pos = [vec![0.0; len], vec![0.0; len], vec![0.0; len]];
        for i in 0..n {
            for p in pos.iter_mut() {
                p[i] = rnd() * 2.0 - 1.0;
            }
        }
        let cons: Vec<DistanceInput> = (0..m)
            .filter_map(|_| {
                let a = (rnd() * n as f32) as u32 % n as u32;
                let b = (rnd() * n as f32) as u32 % n as u32;
                (a != b).then(|| DistanceInput {
                    a,
                    b,
                    rest: rnd(),
                    compliance: if rnd() < 0.3 { 0.0 } else { rnd() * 1e-3 },
                })
            })
            .collect();
        (DistanceSet::new(&cons, len, (len - 1) as u32), pos)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        /// SIMD (serial and parallel on 1 and 2 threads) equals the scalar twin bit for bit.
        #[test]
        fn spring_kernel_simd_matches_scalar_bitwise(n in 2usize..400, m in 0usize..6000, seed in 1u64..u64::MAX) {
            let (set, pos) = setup(n, m, seed);
            let len = pos[0].len();
            let x = [&pos[0][..], &pos[1][..], &pos[2][..]];
            let run = |mode: u8| {
                let mut f = [vec![0.0f32; len], vec![0.0f32; len], vec![0.0f32; len]];
                let [a, b, c] = &mut f;
                match mode {
                    0 => add_spring_forces_scalar(&set, x, [a, b, c], 500.0),
                    1 => add_spring_forces_simd(&set, x, [a, b, c], 500.0, false),
                    t => rayon::ThreadPoolBuilder::new().num_threads(t as usize - 1).build().unwrap()
                        .install(|| add_spring_forces_simd(&set, x, [a, b, c], 500.0, true)),
                }
                f.map(|v| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>())
            };
            let s = run(0);
            prop_assert_eq!(&s, &run(1));
            prop_assert_eq!(&s, &run(2));
            prop_assert_eq!(&s, &run(3));
        }
    }

    #[test]
    fn stretched_spring_pulls_ends_together_and_stores_energy() {
        let cons = [DistanceInput {
            a: 0,
            b: 1,
            rest: 1.0,
            compliance: 0.01,
        }];
        let set = DistanceSet::new(&cons, 8, 7);
        let mut x = vec![0.0; 8];
        x[1] = 1.5;
        let zeros = vec![0.0; 8];
        let mut f = [vec![0.0; 8], vec![0.0; 8], vec![0.0; 8]];
        let [a, b, c] = &mut f;
        add_spring_forces_simd(&set, [&x, &zeros, &zeros], [a, b, c], 1.0, false);
        assert_eq!((f[0][0], f[0][1]), (50.0, -50.0));
        let e = spring_energy(&set, [&x, &zeros, &zeros], 1.0);
        assert!((e - 0.5 * 100.0 * 0.25).abs() < 1e-9, "{e}");
    }
}
