//! Strands (hair) and sheets drawn as smooth curves and surfaces.
//!
//! Today this holds the NURBS machinery of SEEDS.md B ([`nurbs`]) and the timing function of
//! its reproduction ([`nurbs_timing`]). Strand physics and AHS root placement (attaching hairs
//! to a scalp) come later and will build on these curves.

pub mod nurbs;
pub mod nurbs_timing;
