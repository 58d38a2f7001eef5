//! The wind force stage (when the scene names wind). Wind is an aerodynamic force per triangle from the air's velocity relative to the triangle
//! (so a flag flaps rather than translating):
//!
//! ```text
//! v_rel = v_wind(t) - (v_a + v_b + v_c) / 3,   n = unit normal,   A = area
//! F     = ½ ρ C_d A (n·v_rel) |n·v_rel| n      (a third to each corner)
//! v_wind(t) = v_wind (1 + gust sin(2π f t))
//! ```
//!
//! Strand points (hair, [`crate::strands::hair`]) have no triangles; each feels a drag from the
//! air moving past it, `F = ½ ρ C_d A |v_rel| v_rel` with `v_rel = v_wind(t) - v` and `A` its
//! cross-section (thickness × segment length), added to the same per-particle force arrays. A
//! world without strands carries no area array and skips the term.
//!
//! Wind forces are computed per triangle, eight triangles at a time (their corners gathered
//! into lanes, the scalar function's operations lane by lane, so the same bits) in parallel
//! chunks, then gathered per particle through a particle→triangle adjacency in a fixed order,
//! so the sum does not depend on threads. The serial scalar path is the twin.

use rayon::prelude::*;

use crate::data::exec::Exec;
use crate::data::lanes::{finite_lanes, gather1, gather1_unchecked, idx8, F32s, Idx8, Vec3x8, LANES};
use crate::model::effects::{probe, Wind};

/// Triangles one parallel task computes (a multiple of the lane width).
const TRI_CHUNK: usize = 1024;

/// Scratch for the wind force: per-triangle forces, adjacency, per-particle forces.
#[derive(Clone, Debug, Default)]
pub struct WindState {
    tri_force: Vec<[f32; 3]>,
    adj_first: Vec<u32>,
    adj_tri: Vec<u32>,
    /// Per-particle force, N (padded length).
    pub fx: Vec<f32>,
    /// Per-particle force, N.
    pub fy: Vec<f32>,
    /// Per-particle force, N.
    pub fz: Vec<f32>,
    /// Strand drag cross-section per particle, m² (padded length; empty when the world has no
    /// strands, and then the drag costs nothing).
    pub strand_area: Vec<f32>,
}

impl WindState {
    /// Builds the adjacency for `triangles` over `padded_len` particles.
    pub fn new(triangles: &[[u32; 3]], padded_len: usize) -> Self {
        let mut count = vec![0u32; padded_len + 1];
        for t in triangles {
            for &i in t {
                count[i as usize + 1] += 1;
            }
        }
        for i in 0..padded_len {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut adj = vec![0u32; triangles.len() * 3];
        for (k, t) in triangles.iter().enumerate() {
            for &i in t {
                adj[fill[i as usize] as usize] = k as u32;
                fill[i as usize] += 1;
            }
        }
        WindState {
            tri_force: vec![[0.0; 3]; triangles.len()],
            adj_first: count,
            adj_tri: adj,
            fx: vec![0.0; padded_len],
            fy: vec![0.0; padded_len],
            fz: vec![0.0; padded_len],
            strand_area: Vec::new(),
        }
    }

    /// Computes per-particle wind forces from positions and velocities at time `t`: the
    /// triangles' forces in lanes when `exec` has them, in parallel chunks when it is
    /// parallel; the same forces either way.
    #[allow(clippy::too_many_arguments)]
    pub fn compute(&mut self, wind: &Wind, t: f64, tris: &[[u32; 3]], x: [&[f32]; 3], v: [&[f32]; 3], exec: Exec) {
        probe::enter(probe::WIND);
        let s = 1.0 + wind.gust * (2.0 * std::f64::consts::PI * wind.gust_frequency as f64 * t).sin() as f32;
        let air = [wind.velocity[0] * s, wind.velocity[1] * s, wind.velocity[2] * s];
        let k = 0.5 * wind.air_density * wind.drag_coefficient;
        let (simd, parallel) = (exec.simd(), exec.parallel());
        let forces = |(out, t): (&mut [[f32; 3]], &[[u32; 3]])| triangle_forces(t, x, v, air, k, simd, out);
        if parallel {
            self.tri_force
                .par_chunks_mut(TRI_CHUNK)
                .zip(tris.par_chunks(TRI_CHUNK))
                .for_each(forces);
        } else {
            forces((&mut self.tri_force[..], tris));
        }
        let (first, adj, tf, area) = (&self.adj_first, &self.adj_tri, &self.tri_force, &self.strand_area);
        let gather = |i: usize| {
            let mut f = [0.0f32; 3];
            for &t in &adj[first[i] as usize..first[i + 1] as usize] {
                let g = tf[t as usize];
                f[0] += g[0];
                f[1] += g[1];
                f[2] += g[2];
            }
            if !area.is_empty() && area[i] > 0.0 {
                let d = strand_drag(area[i], [v[0][i], v[1][i], v[2][i]], air, k);
                f[0] += d[0];
                f[1] += d[1];
                f[2] += d[2];
            }
            f
        };
        if parallel {
            (self.fx.par_iter_mut(), self.fy.par_iter_mut(), self.fz.par_iter_mut())
                .into_par_iter()
                .enumerate()
                .with_min_len(4096)
                .for_each(|(i, (fx, fy, fz))| {
                    let f = gather(i);
                    (*fx, *fy, *fz) = (f[0], f[1], f[2]);
                });
        } else {
            for i in 0..self.fx.len() {
                let f = gather(i);
                (self.fx[i], self.fy[i], self.fz[i]) = (f[0], f[1], f[2]);
            }
        }
    }
}

/// Wind drag on one strand point: `F = k A |v_rel| v_rel` with `k = ½ ρ C_d`, `A` the point's
/// cross-section (strand thickness times segment length) and `v_rel = v_wind(t) - v` the air's
/// velocity relative to the point. The force grows with the relative air velocity (quadratic
/// drag, like the triangles' law) and vanishes once the point moves with the air.
#[inline]
fn strand_drag(area: f32, v: [f32; 3], air: [f32; 3], k: f32) -> [f32; 3] {
    let rel = [air[0] - v[0], air[1] - v[1], air[2] - v[2]];
    let speed = (rel[0] * rel[0] + rel[1] * rel[1] + rel[2] * rel[2]).sqrt();
    let m = k * area * speed;
    [rel[0] * m, rel[1] * m, rel[2] * m]
}

/// The forces of the triangles `tris` into `out` (one each, as many as both hold): eight at
/// a time with `simd` ([`triangle_forces_lanes`]), the rest, or all, by [`triangle_force`],
/// the twin.
fn triangle_forces(tris: &[[u32; 3]], x: [&[f32]; 3], v: [&[f32]; 3], air: [f32; 3], k: f32, simd: bool, out: &mut [[f32; 3]]) {
    let tris = &tris[..tris.len().min(out.len())];
    let mut done = 0;
    if simd {
        let groups = tris.chunks_exact(LANES);
        done = tris.len() - groups.remainder().len();
        for (t8, o8) in groups.zip(out.chunks_exact_mut(LANES)) {
            triangle_forces_lanes(t8, x, v, air, k, o8);
        }
    }
    for (o, t) in out[done..].iter_mut().zip(&tris[done..]) {
        *o = triangle_force(t, x, v, air, k);
    }
}

/// [`triangle_force`] of eight triangles in lanes: the corners gathered, then the scalar
/// function's operations in its order (no FMA), a degenerate or non-finite triangle's lane
/// set to zero as the scalar function returns zero.
#[inline]
fn triangle_forces_lanes(t8: &[[u32; 3]], x: [&[f32]; 3], v: [&[f32]; 3], air: [f32; 3], k: f32, out: &mut [[f32; 3]]) {
    let corner = |c: usize| idx8(|l| t8[l][c]);
    let (ia, ib, ic) = (corner(0), corner(1), corner(2));
    // One check of the largest corner against every array for all nine gathers.
    let top = ia.iter().chain(&ib).chain(&ic).copied().max().unwrap_or(0) as usize;
    let inside = x.iter().chain(&v).all(|a| top < a.len());
    let at = |a: [&[f32]; 3], i: &Idx8| {
        if inside {
            // SAFETY: every corner is at most `top`, below every array's length (checked).
            unsafe {
                Vec3x8 {
                    x: gather1_unchecked(a[0], i),
                    y: gather1_unchecked(a[1], i),
                    z: gather1_unchecked(a[2], i),
                }
            }
        } else {
            Vec3x8 {
                x: gather1(a[0], i),
                y: gather1(a[1], i),
                z: gather1(a[2], i),
            }
        }
    };
    let pa = at(x, &ia);
    let (e1, e2) = (at(x, &ib) - pa, at(x, &ic) - pa);
    let n = Vec3x8 {
        x: e1.y * e2.z - e1.z * e2.y,
        y: e1.z * e2.x - e1.x * e2.z,
        z: e1.x * e2.y - e1.y * e2.x,
    };
    let n2 = n.length_sq().sqrt();
    // The scalar function's `n2 <= 1e-20 || !n2.is_finite()` is false exactly here (NaN too).
    let ok = n2.simd_gt(F32s::splat(1e-20)) & finite_lanes(n2);
    let area = F32s::splat(0.5) * n2;
    let nh = n / n2;
    let third = F32s::splat(1.0 / 3.0);
    let vt = (at(v, &ia) + at(v, &ib) + at(v, &ic)).scale(third);
    let rel = Vec3x8::splat(air) - vt;
    let vn = nh.dot(rel);
    let m = F32s::splat(k) * area * vn * vn.abs() * third;
    let f = Vec3x8::select(ok, nh.scale(m), Vec3x8::splat([0.0; 3]));
    let (fx, fy, fz) = (f.x.to_array(), f.y.to_array(), f.z.to_array());
    for (l, o) in out.iter_mut().enumerate() {
        *o = [fx[l], fy[l], fz[l]];
    }
}

/// Force on each corner of one triangle (a third of the triangle's force).
#[inline]
fn triangle_force(t: &[u32; 3], x: [&[f32]; 3], v: [&[f32]; 3], air: [f32; 3], k: f32) -> [f32; 3] {
    let [a, b, c] = [t[0] as usize, t[1] as usize, t[2] as usize];
    let e1 = [x[0][b] - x[0][a], x[1][b] - x[1][a], x[2][b] - x[2][a]];
    let e2 = [x[0][c] - x[0][a], x[1][c] - x[1][a], x[2][c] - x[2][a]];
    let n = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    let n2 = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if n2 <= 1e-20 || !n2.is_finite() {
        return [0.0; 3];
    }
    let area = 0.5 * n2;
    let nh = [n[0] / n2, n[1] / n2, n[2] / n2];
    let third = 1.0 / 3.0;
    let vt = [
        (v[0][a] + v[0][b] + v[0][c]) * third,
        (v[1][a] + v[1][b] + v[1][c]) * third,
        (v[2][a] + v[2][b] + v[2][c]) * third,
    ];
    let rel = [air[0] - vt[0], air[1] - vt[1], air[2] - vt[2]];
    let vn = nh[0] * rel[0] + nh[1] * rel[1] + nh[2] * rel[2];
    let m = k * area * vn * vn.abs() * third;
    [nh[0] * m, nh[1] * m, nh[2] * m]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::signed;

    /// The triangles' forces in lanes equal the scalar twin's bit for bit, and the particles'
    /// forces are the same on every backend and thread count: random triangles over a cloud of
    /// particles (lengths around the lane width and past a parallel chunk) with degenerate ones
    /// among them (a repeated corner, collinear corners, a non-finite corner, a corner at the
    /// float range's end whose normal overflows).
    #[test]
    fn triangle_lanes_equal_the_scalar_twin() {
        let mut rng = signed(12);
        let n = 400;
        let mut x: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| rng()).collect());
        let v: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| 3.0 * rng()).collect());
        (x[0][3], x[1][4], x[2][5]) = (f32::NAN, f32::INFINITY, 3e38);
        for c in &mut x {
            (c[6], c[7], c[8]) = (0.0, 1.0, 2.0); // collinear: 6, 7, 8 along (1, 1, 1)
        }
        let pick = |r: f32| ((r + 1.0) * 0.5 * (n - 1) as f32) as u32;
        let mut tris: Vec<[u32; 3]> = (0..TRI_CHUNK + 45).map(|_| [pick(rng()), pick(rng()), pick(rng())]).collect();
        tris[1] = [9, 9, 10];
        tris[2] = [6, 7, 8];
        tris[9] = [3, 1, 2];
        tris[10] = [4, 1, 2];
        tris[12] = [5, 11, 13];
        let (xs, vs) = ([&x[0][..], &x[1][..], &x[2][..]], [&v[0][..], &v[1][..], &v[2][..]]);
        let (air, k) = ([4.0, -1.0, 2.5], 0.6);
        let bits = |f: &[[f32; 3]]| f.iter().flatten().map(|c| c.to_bits()).collect::<Vec<u32>>();
        for len in [0, 5, 8, 13, 64, tris.len()] {
            let (mut lanes, mut twin) = (vec![[7.0; 3]; len], vec![[7.0; 3]; len]);
            triangle_forces(&tris[..len], xs, vs, air, k, true, &mut lanes);
            triangle_forces(&tris[..len], xs, vs, air, k, false, &mut twin);
            assert_eq!(bits(&lanes), bits(&twin), "{len} triangles");
        }
        let mut all = vec![[0.0; 3]; tris.len()];
        triangle_forces(&tris, xs, vs, air, k, true, &mut all);
        assert!(all[1..3].iter().all(|f| *f == [0.0; 3]), "degenerate: {:?}", &all[1..3]);
        assert!(all[9..11].iter().chain(&all[12..13]).all(|f| *f == [0.0; 3]), "non-finite");
        assert!(all.iter().filter(|f| f.iter().all(|c| *c != 0.0)).count() > tris.len() / 2);
        let wind = Wind {
            velocity: air,
            gust: 0.3,
            ..Wind::default()
        };
        let per_particle = |exec: Exec| {
            let mut s = WindState::new(&tris, n);
            s.compute(&wind, 0.7, &tris, xs, vs, exec);
            [s.fx, s.fy, s.fz].map(|a| a.iter().map(|c| c.to_bits()).collect::<Vec<u32>>())
        };
        let want = per_particle(Exec::Scalar);
        for exec in [Exec::Simd, Exec::Parallel, Exec::ScalarParallel] {
            assert_eq!(per_particle(exec), want, "{exec:?}");
        }
    }

    #[test]
    fn wind_pushes_a_facing_triangle_along_its_normal() {
        let tris = [[0u32, 1, 2]];
        let x = [
            vec![0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            vec![0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            vec![0.0; 8],
        ];
        let v = [vec![0.0; 8], vec![0.0; 8], vec![0.0; 8]];
        let mut s = WindState::new(&tris, 8);
        let wind = Wind {
            velocity: [0.0, 0.0, 10.0],
            ..Wind::default()
        };
        s.compute(&wind, 0.0, &tris, [&x[0], &x[1], &x[2]], [&v[0], &v[1], &v[2]], Exec::Scalar);
        // Area 0.5, F = 0.5 * 1.2 * 1 * 0.5 * 100 = 30 N, 10 N per corner, along +z.
        for i in 0..3 {
            assert!((s.fz[i] - 10.0).abs() < 1e-4, "{}", s.fz[i]);
            assert_eq!(s.fx[i], 0.0);
        }
        assert_eq!(s.fz[3], 0.0);
        // Edge-on wind gives no force.
        let wind = Wind {
            velocity: [10.0, 0.0, 0.0],
            ..Wind::default()
        };
        s.compute(&wind, 0.0, &tris, [&x[0], &x[1], &x[2]], [&v[0], &v[1], &v[2]], Exec::Parallel);
        assert!(s.fz[0].abs() < 1e-6 && s.fx[0].abs() < 1e-6);
    }
}
