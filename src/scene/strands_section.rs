//! The `[[strands]]` table: hair grown on a scalp (see [`crate::strands::hair`]).
//!
//! ```toml
//! [[strands]]
//! count = 5000                # strands
//! points = 16                 # points per strand, root included
//! segment_length = 0.012      # m
//! stretch_compliance = 0.0    # m/N (optional)
//! bend_compliance = 0.002     # m/N (optional)
//! mass = 0.0001               # kg per point (optional)
//! thickness = 0.001           # m, strand diameter (optional)
//! damping = 0.5               # 1/s (optional)
//! scalp = { kind = "sphere", center = [0.0, 1.6, 0.0], radius = 0.1, polar_degrees = [0.0, 100.0] }
//! # or: scalp = { kind = "ellipsoid", center = [...], radii = [0.08, 0.1, 0.09], polar_degrees = [0.0, 110.0] }
//! ```
//!
//! Numbers are range-checked as they are read (line and column of the value); a sphere without
//! `radius` or an ellipsoid without `radii` is reported at the line of the `scalp` table.

use serde::{Deserialize, Serialize};

use super::checked::{Count, Degrees180, NonNegative, Positive, Vec3};
use crate::error::{Result, WeftError};
use crate::strands::{Scalp, StrandsDesc};

/// Scalp shapes a scene can name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ScalpKind {
    /// A sphere (`radius`).
    Sphere,
    /// An ellipsoid (`radii`, x y z).
    Ellipsoid,
}

/// `scalp = { kind = ..., center = ..., radius | radii = ..., polar_degrees = [min, max] }`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneScalp {
    /// Sphere or ellipsoid.
    pub kind: ScalpKind,
    /// Centre, m.
    pub center: Vec3,
    /// Sphere radius, m.
    pub radius: Option<Positive>,
    /// Ellipsoid semi-axes, m.
    pub radii: Option<[Positive; 3]>,
    /// Polar range of the hair patch, degrees from +y (default: the whole surface).
    pub polar_degrees: Option<[Degrees180; 2]>,
}

/// A `[[strands]]` table.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneStrands {
    /// Number of strands.
    pub count: Count,
    /// Points per strand (at least 2).
    pub points: Count,
    /// Segment length, m.
    pub segment_length: Positive,
    /// Stretch compliance, m/N (default 0).
    pub stretch_compliance: Option<NonNegative>,
    /// Bending compliance, m/N.
    pub bend_compliance: Option<NonNegative>,
    /// Mass per point, kg.
    pub mass: Option<Positive>,
    /// Strand diameter, m.
    pub thickness: Option<NonNegative>,
    /// Damping rate, 1/s.
    pub damping: Option<NonNegative>,
    /// The scalp.
    pub scalp: toml::Spanned<SceneScalp>,
}

impl SceneScalp {
    /// The scalp.
    pub fn scalp(&self) -> Result<Scalp> {
        let polar = self.polar_degrees.map_or([0.0, 180.0], |p| [p[0].0, p[1].0]);
        let radii = match (self.kind, self.radius, self.radii) {
            (ScalpKind::Sphere, Some(r), None) => [r.0; 3],
            (ScalpKind::Ellipsoid, None, Some(r)) => r.map(|v| v.0),
            (ScalpKind::Sphere, _, _) => {
                return Err(WeftError::param(
                    "scalp",
                    "sphere",
                    "a sphere scalp takes `radius` (and not `radii`)",
                ))
            }
            (ScalpKind::Ellipsoid, _, _) => {
                return Err(WeftError::param(
                    "scalp",
                    "ellipsoid",
                    "an ellipsoid scalp takes `radii` (and not `radius`)",
                ))
            }
        };
        let s = Scalp::ellipsoid(self.center.0, radii, polar);
        s.validate()?;
        Ok(s)
    }
}

impl SceneStrands {
    /// The strands description.
    pub fn desc(&self) -> Result<StrandsDesc> {
        let d = StrandsDesc::default();
        Ok(StrandsDesc {
            scalp: self.scalp.get_ref().scalp()?,
            count: self.count.0,
            points: self.points.0,
            segment_length: self.segment_length.0,
            stretch_compliance: self.stretch_compliance.map_or(d.stretch_compliance, |v| v.0),
            bend_compliance: self.bend_compliance.map_or(d.bend_compliance, |v| v.0),
            mass: self.mass.map_or(d.mass, |v| v.0),
            thickness: self.thickness.map_or(d.thickness, |v| v.0),
            damping: self.damping.map_or(d.damping, |v| v.0),
        })
    }
}
