//! NURBS curves and surfaces with local evaluation (the thesis on NURBS strands and surfaces, section 2.2).
//!
//! A NURBS curve of degree `p` over control points `P_i` with weights `w_i > 0` is
//!
//! ```text
//! C(u) = Σ_i N_{i,p}(u) w_i P_i / Σ_i N_{i,p}(u) w_i          u in [0, 1]
//! ```
//!
//! and a surface is the tensor product `S(u,v) = Σ_ij N_{i,pu}(u) N_{j,pv}(v) w_ij P_ij / Σ_ij
//! N_{i,pu}(u) N_{j,pv}(v) w_ij`. The B-spline basis `N_{i,p}` is given by the Cox–de Boor
//! recursion over a knot vector ([`basis`], [`knots`]).
//!
//! **Degree and order.** The paper writes the *order* `k` (its `N_{i,1}` is piecewise
//! constant); weft's API takes the *degree* `p = k - 1`. The paper's `n + 1` control points
//! are our `n_ctrl`.
//!
//! **The paper's point: local evaluation.** `N_{i,p}` is zero outside `[t_i, t_{i+p+1})`, so at
//! any `u` only `k = p + 1` basis functions are non-zero. Formula 2.8 sums over all `n`
//! control points (cost `O(n)` per point, `O(n m)` for a surface); formula 2.11 sums only over
//! a window `[now - k, now + k]` around the point (cost `O(k)`, `O(ku kv)`), and moving one
//! control point changes the curve only over `k` knot spans. Here `eval_global` is the first
//! (the `f64` reference), `eval_local` the second (find the span, O(1) for uniform knots; the
//! `p + 1` non-zero basis values by the triangular scheme; `f32`), and the batch evaluators
//! (`eval_many`, `eval_grid`) run the local scheme with SIMD and have scalar twins.
//!
//! **Tolerances.** Local (`f32`) and global (`f64`) evaluation of the same curve agree to
//! `1e-6` times the largest control-point coordinate (property tests, degrees 1..5, up to 64
//! control points per direction, weights in `[0.2, 5]`). SIMD batch and scalar twins agree bit
//! for bit.
//!
//! **Knot vector.** The paper's formula 2.9, as printed, has an off-by-one denominator that
//! makes the last control point inert; weft uses the textbook clamped uniform vector and keeps
//! the printed one for reproduction ([`KnotVector::paper_verbatim`]; see [`knots`]).
//!
//! **Parameters** outside `[0, 1]` (or NaN) are an error, never clamped silently.

pub mod basis;
mod curve;
mod curve_batch;
pub mod knots;
mod render;
mod surface;
mod surface_batch;
#[cfg(test)]
mod tests;

pub use basis::{basis_global, basis_local, GlobalScratch, MAX_ORDER};
pub use curve::NurbsCurve;
pub use knots::{KnotVector, MAX_CONTROL, MAX_DEGREE};
pub use render::{CurveSamples, SurfaceMesh};
pub use surface::NurbsSurface;
