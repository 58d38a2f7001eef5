//! Strands (hair) on a scalp, and the smooth curves and surfaces they are drawn with.
//!
//! - [`hair`]: the AHS builder (attaching hairs to a scalp, from the NURBS thesis): roots spread over a scalp, each strand grown along
//!   the scalp normal, simulated as particles with stretch and bending distance constraints;
//! - [`scalp`]: the scalp shape, the Fibonacci root placement and the scalp collision stage;
//! - `attach`: adding strands to a world (`World::add_strands`);
//! - [`nurbs`]: NURBS curves and surfaces with global and local evaluation, used to draw strands
//!   and cloth smoothly; [`nurbs_timing`] measures global against local evaluation.

pub mod hair;
pub mod nurbs;
pub mod nurbs_timing;
pub mod scalp;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_paths;

pub use crate::model::layout::StrandInfo;
pub use hair::{StrandsBuild, StrandsDesc};
pub use scalp::Scalp;
