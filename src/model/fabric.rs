//! Fabric descriptions and the four presets of the VcCPBD paper (Shapri, Sulaiman & Bade 2016).
//!
//! The paper gives, per fabric, the time step, the particle mass and a damping coefficient:
//!
//! | preset | dt (s) | mass (g) | damping |
//! |---|---|---|---|
//! | basic | 0.06 | 1.0 | 0.80 |
//! | cotton | 0.05 | 2.1 | 0.81 |
//! | wool | 0.05 | 1.9 | 0.74 |
//! | polyester | 0.05 | 2.5 | 0.55 |
//!
//! It gives no stiffness or thickness; the compliances and thicknesses below are weft's own
//! choices (stiff in stretch, softer in shear, softest in bending, wool the softest and
//! thickest, polyester the thinnest), stated here so they stay stable.
//!
//! Damping is a linear velocity damping rate `c` in 1/s, applied after each substep of length
//! `h` as `v <- v / (1 + c h)`: unconditionally stable, and the paper's coefficients give mild
//! damping at its time steps.

use crate::error::{mass, non_negative, positive, Result, WeftError};

/// Material of one cloth piece.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fabric {
    /// Mass of one particle, kg.
    pub mass: f32,
    /// XPBD compliance of stretch constraints, m/N (0 = rigid).
    pub stretch_compliance: f32,
    /// XPBD compliance of shear constraints, m/N.
    pub shear_compliance: f32,
    /// XPBD compliance of bending (distance-two) constraints, m/N.
    pub bend_compliance: f32,
    /// Linear velocity damping rate, 1/s.
    pub damping: f32,
    /// Thickness, m (collision distance of the cloth).
    pub thickness: f32,
    /// The time step the fabric was tuned for, s (used when a scene gives none).
    pub dt: f32,
}

impl Default for Fabric {
    fn default() -> Self {
        Fabric::preset("basic").expect("basic preset exists")
    }
}

/// Names of the built-in presets.
pub const PRESETS: [&str; 4] = ["basic", "cotton", "wool", "polyester"];

impl Fabric {
    /// One of the paper's presets: `basic`, `cotton`, `wool`, `polyester`.
    pub fn preset(name: &str) -> Result<Fabric> {
        let f = |dt: f32, grams: f32, damping: f32, stretch: f32, shear: f32, bend: f32, thickness: f32| Fabric {
            mass: grams * 1e-3,
            stretch_compliance: stretch,
            shear_compliance: shear,
            bend_compliance: bend,
            damping,
            thickness,
            dt,
        };
        Ok(match name {
            "basic" => f(0.06, 1.0, 0.80, 0.0, 1e-6, 1e-4, 0.002),
            "cotton" => f(0.05, 2.1, 0.81, 1e-8, 1e-6, 2e-5, 0.001),
            "wool" => f(0.05, 1.9, 0.74, 1e-7, 1e-5, 5e-4, 0.003),
            "polyester" => f(0.05, 2.5, 0.55, 0.0, 5e-7, 5e-5, 0.0005),
            other => {
                return Err(WeftError::param(
                    "fabric",
                    other,
                    format!("unknown preset; expected one of {}", PRESETS.join(", ")),
                ))
            }
        })
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        mass("fabric.mass", self.mass)?;
        non_negative("fabric.stretch_compliance", self.stretch_compliance)?;
        non_negative("fabric.shear_compliance", self.shear_compliance)?;
        non_negative("fabric.bend_compliance", self.bend_compliance)?;
        non_negative("fabric.damping", self.damping)?;
        non_negative("fabric.thickness", self.thickness)?;
        positive("fabric.dt", self.dt)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_carry_the_papers_numbers() {
        let c = Fabric::preset("cotton").unwrap();
        assert_eq!((c.dt, c.mass, c.damping), (0.05, 2.1e-3, 0.81));
        let b = Fabric::preset("basic").unwrap();
        assert_eq!((b.dt, b.mass, b.damping), (0.06, 1.0e-3, 0.80));
        for p in PRESETS {
            Fabric::preset(p).unwrap().validate().unwrap();
        }
    }

    #[test]
    fn unknown_preset_is_an_error() {
        let e = Fabric::preset("silk").unwrap_err().to_string();
        assert!(e.contains("silk") && e.contains("cotton"), "{e}");
    }

    #[test]
    fn negative_mass_is_rejected() {
        let f = Fabric {
            mass: -1.0,
            ..Fabric::default()
        };
        assert!(f.validate().unwrap_err().to_string().contains("fabric.mass"));
        let f = Fabric {
            damping: f32::NAN,
            ..Fabric::default()
        };
        assert!(f.validate().is_err());
    }
}
