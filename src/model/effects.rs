//! External effects: gravity, wind and linear drag — each present only when the scene names it.
//!
//! Gravity and drag are folded into the predict kernel (see [`crate::integrate`]); a kernel
//! variant is compiled per combination, so an effect not named costs nothing in the loop.
//! The wind force stage is `crate::integrate::wind`.
use crate::error::{finite3, non_negative, positive, Result};

/// Wind as an effect.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Wind {
    /// Mean air velocity, m/s.
    pub velocity: [f32; 3],
    /// Air density, kg/m³.
    #[serde(default = "default_density")]
    pub air_density: f32,
    /// Drag coefficient of the fabric (dimensionless).
    #[serde(default = "default_cd")]
    pub drag_coefficient: f32,
    /// Relative gust amplitude (0 = steady).
    #[serde(default)]
    pub gust: f32,
    /// Gust frequency, Hz.
    #[serde(default = "default_gust_frequency")]
    pub gust_frequency: f32,
}

fn default_density() -> f32 {
    1.2
}
fn default_cd() -> f32 {
    1.0
}
fn default_gust_frequency() -> f32 {
    0.5
}

impl Default for Wind {
    fn default() -> Self {
        Wind {
            velocity: [5.0, 0.0, 0.0],
            air_density: 1.2,
            drag_coefficient: 1.0,
            gust: 0.0,
            gust_frequency: 0.5,
        }
    }
}

/// The effects a scene names. `None` means absent: no pass, no allocation, no branch in a loop.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Effects {
    /// Gravitational acceleration, m/s².
    pub gravity: Option<[f32; 3]>,
    /// Wind.
    pub wind: Option<Wind>,
    /// Linear drag coefficient, kg/s (force `-c v` on every particle).
    pub drag: Option<f32>,
}

impl Effects {
    /// Earth gravity along -y and nothing else.
    pub fn gravity() -> Self {
        Effects {
            gravity: Some([0.0, -9.81, 0.0]),
            ..Default::default()
        }
    }

    /// Checks every named effect.
    pub fn validate(&self) -> Result<()> {
        if let Some(g) = self.gravity {
            finite3("effects.gravity", g)?;
        }
        if let Some(d) = self.drag {
            non_negative("effects.drag", d)?;
        }
        if let Some(w) = &self.wind {
            finite3("effects.wind.velocity", w.velocity)?;
            positive("effects.wind.air_density", w.air_density)?;
            non_negative("effects.wind.drag_coefficient", w.drag_coefficient)?;
            non_negative("effects.wind.gust", w.gust)?;
            non_negative("effects.wind.gust_frequency", w.gust_frequency)?;
        }
        Ok(())
    }

    /// Names of the effects that are on.
    pub fn named(&self) -> Vec<&'static str> {
        let mut v = Vec::new();
        if self.gravity.is_some() {
            v.push("gravity");
        }
        if self.wind.is_some() {
            v.push("wind");
        }
        if self.drag.is_some() {
            v.push("drag");
        }
        v
    }
}

/// Counts entries into each effect's kernel code on the current thread, in tests only (an
/// empty inline function otherwise): the proof that an effect not named costs nothing is that
/// its code is never entered ([`probe::GRAVITY`], [`probe::DRAG`], [`probe::WIND`]).
pub(crate) mod probe {
    /// Gravity's terms (predict, kick, implicit right-hand side).
    pub(crate) const GRAVITY: usize = 0;
    /// Drag's terms.
    pub(crate) const DRAG: usize = 1;
    /// The wind force pass.
    pub(crate) const WIND: usize = 2;

    #[cfg(test)]
    thread_local! {
        static COUNTS: std::cell::Cell<[u64; 3]> = const { std::cell::Cell::new([0; 3]) };
    }

    /// Records one entry into effect `e`'s code.
    #[inline(always)]
    pub(crate) fn enter(e: usize) {
        #[cfg(test)]
        COUNTS.with(|c| {
            let mut v = c.get();
            v[e] += 1;
            c.set(v);
        });
        #[cfg(not(test))]
        let _ = e;
    }

    /// The entries counted on this thread so far, and resets them.
    #[cfg(test)]
    pub(crate) fn take() -> [u64; 3] {
        COUNTS.with(|c| c.replace([0; 3]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation_names_the_key() {
        let e = Effects {
            drag: Some(-1.0),
            ..Default::default()
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(e.contains("effects.drag"), "{e}");
        let e = Effects {
            gravity: Some([0.0, f32::NAN, 0.0]),
            ..Default::default()
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(e.contains("effects.gravity"), "{e}");
    }
}

#[cfg(test)]
mod probe_tests {
    use super::*;
    use crate::model::params::{Backend, Method, SolverParams};
    use crate::{ClothDesc, PinSpec, World};

    /// Every method and backend, every subset of gravity, drag and wind: a named effect's code
    /// is entered, an unnamed one's never (counted on this thread; the world runs on it).
    #[test]
    fn an_effect_not_named_is_never_entered() {
        for method in Method::ALL {
            for backend in [Backend::Simd, Backend::Scalar] {
                for mask in 0..8u8 {
                    let effects = Effects {
                        gravity: (mask & 1 != 0).then_some([0.0, -9.81, 0.0]),
                        drag: (mask & 2 != 0).then_some(0.0),
                        wind: (mask & 4 != 0).then(|| Wind {
                            velocity: [0.0; 3],
                            ..Wind::default()
                        }),
                    };
                    let params = SolverParams {
                        method,
                        backend,
                        substeps: 4,
                        stiffness: 20.0,
                        ..SolverParams::default()
                    };
                    let mut w = World::new(params, effects).unwrap();
                    w.set_caller_thread_only(true);
                    w.add_cloth(&ClothDesc {
                        rows: 6,
                        cols: 6,
                        pins: vec![PinSpec::FirstRowCorners],
                        // Soft springs (zero compliance reads as `stiffness`): explicit methods stay stable.
                        fabric: crate::Fabric {
                            stretch_compliance: 0.0,
                            shear_compliance: 0.0,
                            bend_compliance: 0.0,
                            ..crate::Fabric::preset("basic").unwrap()
                        },
                        ..ClothDesc::default()
                    })
                    .unwrap();
                    probe::take();
                    for _ in 0..2 {
                        w.step(1.0 / 60.0).unwrap();
                    }
                    let counts = probe::take();
                    for (k, name) in ["gravity", "drag", "wind"].iter().enumerate() {
                        let named = mask & (1 << k) != 0;
                        assert_eq!(
                            counts[k] > 0,
                            named,
                            "{method:?} {backend:?}: {name} named {named}, entered {} times",
                            counts[k]
                        );
                    }
                }
            }
        }
    }
}
