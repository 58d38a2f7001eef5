//! Plain descriptions shared by the world, the scene files and the f64 reference: solver
//! parameters, fabrics, cloth grids, effects, analytic shapes. No kernels, no thread pools:
//! a reader of these types needs nothing but `data/` and the error type.
pub mod budget;
pub mod cloth;
pub mod description;
pub mod effects;
pub mod fabric;
pub mod layout;
pub mod params;
pub mod self_collision;
pub mod shapes;
