//! Energies of a state of the accuracy report's model: the energy drift column and the
//! bounded-blow-up rule ([`super`] module docs).

use super::reference::Reference;
use super::run::{dist, state64};
use crate::World;

/// Kinetic + gravitational + spring energy of `world`'s model at state `(x, v)`, J.
pub fn model_energy(world: &World, x: &[[f64; 3]], v: &[[f64; 3]]) -> f64 {
    let p = world.particles();
    let g = world.effects().gravity.map(|g| g.map(f64::from)).unwrap_or([0.0; 3]);
    let mut e = 0.0;
    for i in 0..x.len() {
        if p.w[i] > 0.0 {
            let m = 1.0 / p.w[i] as f64;
            e += 0.5 * m * (v[i][0] * v[i][0] + v[i][1] * v[i][1] + v[i][2] * v[i][2]);
            e -= m * (g[0] * x[i][0] + g[1] * x[i][1] + g[2] * x[i][2]);
        }
    }
    let stiffness = world.params().stiffness;
    for col in &world.distance_set().colours {
        for k in 0..col.real {
            let (a, b) = (col.a[k] as usize, col.b[k] as usize);
            let l = dist(x[a], x[b]);
            let ks = crate::integrate::springs::spring_stiffness(col.compliance[k], stiffness) as f64;
            e += 0.5 * ks * (l - col.rest[k] as f64).powi(2);
        }
    }
    e
}

/// Kinetic energy `Σ ½ m |v|²` of the free particles of `world` at velocities `v`, J.
pub fn kinetic_energy(world: &World, v: &[[f64; 3]]) -> f64 {
    let w = &world.particles().w;
    v.iter()
        .enumerate()
        .filter(|&(i, _)| w[i] > 0.0)
        .map(|(i, v)| 0.5 * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) / w[i] as f64)
        .sum()
}

/// The reference's energy budget, J: the largest of its kinetic energy (at the start, at the
/// end, and from the mean velocity `(x_{k+1} - x_k)/dt` over each step) and of the
/// gravitational energy it has released, `|E_g(x_k) - E_g(x_0)|`, over the run; at least
/// 1e-9 J. A converged run stays within a few times this; a blow-up that the self-collision
/// clamp keeps finite pumps orders of magnitude more into motion.
pub fn energy_budget(world: &World, reference: &Reference) -> f64 {
    let p = world.particles();
    let g = world.effects().gravity.map(|g| g.map(f64::from)).unwrap_or([0.0; 3]);
    let gravity = |x: &[[f64; 3]]| -> f64 {
        x.iter()
            .enumerate()
            .filter(|&(i, _)| p.w[i] > 0.0)
            .map(|(i, x)| -(g[0] * x[0] + g[1] * x[1] + g[2] * x[2]) / p.w[i] as f64)
            .sum()
    };
    let (_, v0) = state64(world);
    let mut budget = kinetic_energy(world, &v0).max(kinetic_energy(world, &reference.final_velocity));
    let dt = reference.dt as f64;
    if let Some(first) = reference.frames.first() {
        let e0 = gravity(first);
        for pair in reference.frames.windows(2) {
            let v: Vec<[f64; 3]> = pair[0]
                .iter()
                .zip(&pair[1])
                .map(|(a, b)| std::array::from_fn(|k| (b[k] - a[k]) / dt))
                .collect();
            budget = budget.max(kinetic_energy(world, &v)).max((gravity(&pair[1]) - e0).abs());
        }
    }
    budget.max(1e-9)
}
