//! Collision detection. This part holds the broadphase of cloth **self**-collision:
//! finding, for every particle, the particles within a distance `max_dist`.
//!
//! Two methods, one answer:
//! * [`hash::SpatialHash`] — the spatial hash of SEEDS section C (Müller's dense hash: cells of
//!   side `spacing`, counting sort into `cell_start` / `cell_entries`, 27-cell queries). Built
//!   once per step, before the substeps.
//! * [`particle_tree::ParticleTree`] — the box hierarchy of SEEDS section A (VcCPBD): an AABB
//!   tree built once and refitted every step.
//!
//! Both fill a [`neighbours::Neighbours`] (CSR lists, the paper's `firstAdjId` / `adjIds`) with
//! the same canonical result — sorted lists under one shared `f32` predicate — which also
//! equals the O(n²) brute force [`neighbours::Neighbours::fill_brute_force`]. Every parallel
//! routine has a `_serial` twin, and the results do not depend on the thread count.
pub mod hash;
pub mod neighbours;
pub mod particle_tree;
