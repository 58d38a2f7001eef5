//! Integration kernels of the position-based step: predict and update.
//!
//! Per substep of length `h` (Müller et al. 2006, Algorithm 1; XPBD substepping as in Macklin
//! et al. 2019 "Small Steps in Physics Simulation"):
//!
//! ```text
//! predict:  v <- v + h g + h w f_ext;  v <- v / (1 + h w c_drag);  p <- x + h v
//! update:   v <- (p - x) / h;  v <- v * k_damp;  x <- p
//! ```
//!
//! Gravity acts only on particles with `w > 0`. Each kernel is compiled for the set of effects
//! the scene names (const generic flags), so an effect that is not named costs no work in the
//! loop and no branch. Every SIMD kernel has a scalar twin in this module with the same
//! operations in the same order (no FMA), tested bit for bit.

pub mod kernels;

pub use kernels::{predict, predict_saving, update, PredictParams};
pub mod implicit;
pub mod mass_spring;
pub mod springs;
pub mod wind;
