//! Constraints: XPBD distance constraints grouped by graph colour, and tethers.
//!
//! XPBD (Macklin, Müller, Chentanez 2016) solves each constraint `C(p) = |p_b - p_a| - rest`
//! with a compliance `α` (inverse stiffness, m/N). Per substep of length `h`, with
//! `α̃ = α / h²` and the accumulated multiplier `λ` (reset each substep):
//!
//! ```text
//! Δλ  = (-C - α̃ λ) / (w_a + w_b + α̃)
//! p_a -= w_a Δλ n,   p_b += w_b Δλ n,   λ += Δλ,   n = (p_b - p_a) / |p_b - p_a|
//! ```
//!
//! With `α = 0` this is PBD's projection (Müller et al. 2006). Constraints are coloured so
//! that no two of one colour share a particle; a colour is then solved in parallel chunks and
//! eight constraints at a time in SIMD, and the result does not depend on chunking or threads.

pub mod blocks;
pub mod colour;
pub mod distance;
pub mod grid;
mod grid_row;
pub mod grid_sweep;
pub mod project;
pub mod tethers;

pub use distance::DistanceSet;
pub use tethers::TetherSet;
