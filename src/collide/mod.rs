//! Collision detection. Mesh obstacles (SEEDS.md section D, Landovskaya, Landovsky &
//! Frolovsky): a validated [`mesh::TriMesh`] (from arrays or [`mesh_obj`] files), three
//! interchangeable face broadphases behind [`face_broadphase::FaceBroadphase`] (the paper's
//! uniform [`grid`], a [`bvh`], a [`face_hash`]), the segment/proximity [`narrow`]phase, the
//! position/velocity [`mesh_response`], the paper's [`face_memory`], parallel [`mesh_batch`]
//! queries and procedural [`dressform`] mannequins. Analytic [`shapes`] (plane, sphere,
//! capsule, box) and the world's [`obstacles`] with their step kernels ([`obstacle_kernels`]).
pub mod bvh;
pub mod dressform;
pub mod face_broadphase;
pub mod face_hash;
pub mod face_memory;
pub mod grid;
pub mod mesh;
pub mod mesh_batch;
pub mod mesh_obj;
pub mod mesh_response;
pub mod narrow;
pub mod obstacle_kernels;
pub mod obstacle_mesh;
pub mod obstacles;
pub mod penetration;
pub mod shapes;
