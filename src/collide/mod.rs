//! Collision detection.
//!
//! **Obstacles** (Landovskaya, Landovsky & Frolovsky): a validated
//! [`mesh::TriMesh`] (from arrays or [`mesh_obj`] files), three interchangeable face
//! broadphases behind [`face_broadphase::FaceBroadphase`] (the paper's uniform [`grid`], a
//! [`bvh`], a [`face_hash`]), the segment/proximity [`narrow`]phase, the position/velocity
//! [`mesh_response`], the paper's [`face_memory`], parallel [`mesh_batch`] queries and
//! procedural [`dressform`] mannequins; analytic [`shapes`] (plane, sphere, capsule, box) and
//! the world's [`obstacles`] with their step kernels ([`obstacle_kernels`]).
//!
//! **Self-collision**: finding, for every particle, the particles within a distance
//! `max_dist`, two methods with one answer:
//! * [`hash::SpatialHash`] — Müller's dense spatial hash ("Ten Minute Physics": cells of
//!   side `spacing`, counting sort into `cell_start` / `cell_entries`, 27-cell queries). Built
//!   once per step, before the substeps.
//! * [`particle_tree::ParticleTree`] — the box hierarchy of the VcCPBD paper (Shapri, Sulaiman & Bade 2016): an AABB
//!   tree built once and refitted every step.
//!
//! Both fill a [`neighbours::Neighbours`] (CSR lists, the paper's `firstAdjId` / `adjIds`) with
//! the same canonical result — sorted lists under one shared `f32` predicate — which also
//! equals the O(n²) brute force [`neighbours::Neighbours::fill_brute_force`]. Every parallel
//! routine has a `_serial` twin, and the results do not depend on the thread count.
pub mod bvh;
pub mod dressform;
pub mod face_ball;
pub mod face_broadphase;
pub mod face_cache;
pub mod face_hash;
pub mod face_memory;
pub mod grid;
pub mod hash;
pub mod mesh;
pub mod mesh_batch;
pub mod mesh_obj;
mod mesh_pass;
pub mod mesh_response;
pub mod narrow;
pub mod neighbours;
pub mod obstacle;
pub mod obstacle_kernels;
pub mod obstacle_mesh;
pub mod obstacles;
pub mod particle_tree;
pub mod penetration;
pub mod response;
mod self_active;
pub mod self_collision;
pub mod self_config;
mod self_mid;
mod self_near;
mod self_near_moves;
mod self_near_scan;
mod self_pairs;
mod self_verlet;
pub mod shapes;
