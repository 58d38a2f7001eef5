//! The data every kernel works on: the lane vocabulary (the only place that knows the SIMD
//! width) and the particles in structure-of-arrays form, padded to whole lanes.
//!
//! Depends on nothing else in the crate.
pub mod exec;
pub mod lanes;
pub mod particles;
