//! Hair strands: the AHS builder (attaching hairs to a scalp, from the NURBS thesis on strands and surfaces) and its physics.
//!
//! AHS, as in the thesis: given a scalp surface `C`, `n` strands of `m` control points and a
//! segment length `leng`, for each root point `P` on `C` take the direction `dir` = the surface
//! normal at `P`; the first control point is `T_1 = P` and each next one
//! `T_{q+1} = T_q + dir · leng`. Roots are spread over the scalp by [`Scalp::roots`] (a
//! Fibonacci spiral). The control points are simulated as particles:
//!
//! - **stretch**: XPBD distance constraints between neighbours `q, q+1` (rest `leng`);
//! - **bending**: distance constraints between `q, q+2` (rest `2 leng`, the straight strand),
//!   softened by their own compliance;
//! - the root `T_1` is pinned (`w = 0`, kinematic: it moves only if the caller moves it);
//! - gravity acts on every free point through the predict stage, and wind as a drag on each
//!   point (see [`crate::model::effects`], strand drag `F = ½ ρ C_d (d · leng) |v_rel| v_rel`);
//! - the scalp stage keeps every free point outside the scalp plus half the strand thickness
//!   (see [`super::scalp`]).
//!
//! Strand `s` occupies the particles `first + s·m .. first + (s+1)·m`, root first, so one
//! strand's points are contiguous and ready to become a [`NurbsCurve::strand`]'s control points.
//!
//! [`NurbsCurve::strand`]: super::nurbs::NurbsCurve::strand

use super::scalp::Scalp;
use crate::error::{mass, non_negative, positive, Result, WeftError};
use crate::model::cloth::{ConstraintKind, Edge, MAX_PARTICLES};

/// A group of strands grown on one scalp.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StrandsDesc {
    /// The scalp the roots sit on.
    pub scalp: Scalp,
    /// Number of strands.
    pub count: u32,
    /// Points per strand, root included (at least 2).
    pub points: u32,
    /// Rest distance between neighbouring points (`leng`), m.
    pub segment_length: f32,
    /// XPBD compliance of the stretch constraints, m/N (0 = inextensible).
    pub stretch_compliance: f32,
    /// XPBD compliance of the bending (distance-two) constraints, m/N.
    pub bend_compliance: f32,
    /// Mass of every free point, kg.
    pub mass: f32,
    /// Strand (wisp) diameter, m: the wind's cross-section and twice the scalp margin.
    pub thickness: f32,
    /// Velocity damping rate, 1/s.
    pub damping: f32,
}

impl Default for StrandsDesc {
    fn default() -> Self {
        StrandsDesc {
            scalp: Scalp::sphere([0.0, 1.6, 0.0], 0.1),
            count: 100,
            points: 16,
            segment_length: 0.015,
            stretch_compliance: 0.0,
            bend_compliance: 1e-3,
            mass: 1e-4,
            thickness: 0.001,
            damping: 0.5,
        }
    }
}

/// The output of [`StrandsDesc::build`], with indices local to the group.
#[derive(Clone, Debug, Default)]
pub struct StrandsBuild {
    /// Rest positions, strand after strand, root first.
    pub positions: Vec<[f32; 3]>,
    /// Inverse masses (0 for the roots).
    pub inv_mass: Vec<f32>,
    /// Stretch and bend constraints.
    pub edges: Vec<Edge>,
    /// Unit growth direction (scalp normal) of each strand.
    pub directions: Vec<[f32; 3]>,
}

impl StrandsDesc {
    /// Upper bounds of what [`build`](Self::build) makes (nothing is built): the counts of the
    /// memory estimate ([`crate::model::budget`]).
    pub fn memory_counts(&self) -> crate::model::budget::MemoryCounts {
        let (n, m) = (self.count as u64, self.points as u64);
        crate::model::budget::MemoryCounts {
            particles: n * m,
            constraints: n.saturating_mul((2 * m).saturating_sub(3)),
            ..Default::default()
        }
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        self.scalp.validate()?;
        if self.count == 0 {
            return Err(WeftError::param("strands.count", self.count, "at least one strand is needed"));
        }
        if self.points < 2 {
            return Err(WeftError::param("strands.points", self.points, "a strand needs at least 2 points"));
        }
        if self.count as u64 * self.points as u64 > MAX_PARTICLES {
            return Err(WeftError::param(
                "strands.count x points",
                format!("{} x {}", self.count, self.points),
                format!("at most {MAX_PARTICLES} particles per strand group"),
            ));
        }
        positive("strands.segment_length", self.segment_length)?;
        non_negative("strands.stretch_compliance", self.stretch_compliance)?;
        non_negative("strands.bend_compliance", self.bend_compliance)?;
        mass("strands.mass", self.mass)?;
        non_negative("strands.thickness", self.thickness)?;
        non_negative("strands.damping", self.damping)?;
        Ok(())
    }

    /// Validates and grows the strands by AHS (module docs).
    pub fn build(&self) -> Result<StrandsBuild> {
        self.validate()?;
        let (n, m) = (self.count as usize, self.points as usize);
        let mut out = StrandsBuild {
            positions: Vec::with_capacity(n * m),
            inv_mass: Vec::with_capacity(n * m),
            edges: Vec::with_capacity(n * (2 * m - 3)),
            directions: Vec::with_capacity(n),
        };
        let leng = self.segment_length as f64;
        for (s, (root, dir)) in self.scalp.roots(n).into_iter().enumerate() {
            for q in 0..m {
                let t = q as f64 * leng;
                out.positions.push([0, 1, 2].map(|k| (root[k] as f64 + dir[k] as f64 * t) as f32));
                out.inv_mass.push(if q == 0 { 0.0 } else { 1.0 / self.mass });
            }
            let base = (s * m) as u32;
            for q in 0..m as u32 - 1 {
                out.edges.push(Edge {
                    a: base + q,
                    b: base + q + 1,
                    rest: self.segment_length,
                    compliance: self.stretch_compliance,
                    kind: ConstraintKind::Stretch,
                });
            }
            for q in 0..(m as u32).saturating_sub(2) {
                out.edges.push(Edge {
                    a: base + q,
                    b: base + q + 2,
                    rest: 2.0 * self.segment_length,
                    compliance: self.bend_compliance,
                    kind: ConstraintKind::Bend,
                });
            }
            out.directions.push(dir);
        }
        Ok(out)
    }
}
