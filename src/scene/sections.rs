//! The tables of a scene file.

use serde::{Deserialize, Serialize};

use super::checked::{Count, Fraction, NonNegative, Positive, Travel, Vec3};
use crate::error::Result;
use crate::model::cloth::{ClothDesc, PinSpec};
use crate::model::effects::{Effects, Wind};
use crate::model::fabric::Fabric;
use crate::model::params::{Backend, Method, SolverParams};
use crate::model::self_collision::{Response, SelfBroadphase, SelfCollision};

/// `[solver]`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSection {
    /// Step length, s (default 1/60).
    #[serde(default = "default_dt")]
    pub dt: Positive,
    /// Substeps per step.
    #[serde(default = "default_substeps")]
    pub substeps: Count,
    /// Solver sweeps per substep.
    #[serde(default = "default_iterations")]
    pub iterations: Count,
    /// Threads (0 = all cores or the calling thread, whichever the world measures faster).
    #[serde(default)]
    pub threads: u16,
    /// Integrator: `"xpbd"` (default), `"symplectic-euler"`, `"leapfrog"`, `"implicit-euler"`.
    #[serde(default)]
    pub method: Method,
    /// Spring stiffness, N/m, of zero-compliance constraints in the force-based methods
    /// (default [`DEFAULT_STIFFNESS`](crate::model::params::DEFAULT_STIFFNESS)).
    pub stiffness: Option<Positive>,
    /// `"simd"` (default) or `"scalar"`.
    #[serde(default)]
    pub backend: Backend,
}

fn default_dt() -> Positive {
    Positive(1.0 / 60.0)
}
fn default_substeps() -> Count {
    Count(8)
}
fn default_iterations() -> Count {
    Count(1)
}

impl Default for SolverSection {
    fn default() -> Self {
        SolverSection {
            dt: default_dt(),
            substeps: default_substeps(),
            iterations: default_iterations(),
            threads: 0,
            backend: Backend::Simd,
            method: Method::Xpbd,
            stiffness: None,
        }
    }
}

impl SolverSection {
    /// The solver parameters.
    pub fn params(&self) -> SolverParams {
        SolverParams {
            dt: self.dt.0,
            substeps: self.substeps.0,
            iterations: self.iterations.0,
            threads: self.threads as usize,
            backend: self.backend,
            method: self.method,
            stiffness: self.stiffness.map_or(crate::model::params::DEFAULT_STIFFNESS, |s| s.0),
            ..SolverParams::default()
        }
    }
}

/// `[effects.wind]`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct WindSection {
    /// Mean air velocity, m/s.
    pub velocity: Vec3,
    /// Air density, kg/m³ (default 1.2).
    pub air_density: Option<Positive>,
    /// Drag coefficient (default 1.0).
    pub drag_coefficient: Option<NonNegative>,
    /// Relative gust amplitude (default 0).
    pub gust: Option<NonNegative>,
    /// Gust frequency, Hz (default 0.5).
    pub gust_frequency: Option<NonNegative>,
}

/// `[effects]`: an effect not named is off.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct EffectsSection {
    /// Gravity, m/s².
    pub gravity: Option<Vec3>,
    /// Linear drag, kg/s.
    pub drag: Option<NonNegative>,
    /// Wind.
    pub wind: Option<WindSection>,
    /// Coulomb friction coefficient against obstacles (default 0; an obstacle may set its own).
    pub friction: Option<NonNegative>,
    /// Self-collision (particle–particle contacts).
    pub self_collision: Option<SelfCollisionSection>,
}

/// `[effects.self_collision]`: every key optional.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SelfCollisionSection {
    /// Collision distance, m (default: min(thickness, spacing) of the cloths).
    pub distance: Option<Positive>,
    /// Friction from 0 to 1 (default 0.3).
    pub friction: Option<Fraction>,
    /// `"pbd"`, `"movement-speed"` or `"vccpbd"` (default).
    pub response: Option<Response>,
    /// `"hash"` (default) or `"aabb-tree"`.
    pub broadphase: Option<SelfBroadphase>,
    /// Measure the average collision after every step (default false; it costs a broadphase
    /// query a step, see [`SelfCollision::measure`]).
    pub measure: Option<bool>,
    /// The travel bound `T / d`, above 0 and at most 2 (default 1; see
    /// [`SelfCollision::travel`]).
    pub travel: Option<Travel>,
}

impl SelfCollisionSection {
    /// The settings.
    pub fn config(&self) -> SelfCollision {
        let d = SelfCollision::default();
        SelfCollision {
            distance: self.distance.map(|v| v.0),
            friction: self.friction.map_or(d.friction, |v| v.0),
            response: self.response.unwrap_or(d.response),
            broadphase: self.broadphase.unwrap_or(d.broadphase),
            measure: self.measure.unwrap_or(d.measure),
            travel: self.travel.map_or(d.travel, |v| v.0),
        }
    }
}

impl EffectsSection {
    /// The effects.
    pub fn effects(&self) -> Effects {
        let d = Wind::default();
        Effects {
            gravity: self.gravity.map(|g| g.0),
            drag: self.drag.map(|d| d.0),
            wind: self.wind.as_ref().map(|w| Wind {
                velocity: w.velocity.0,
                air_density: w.air_density.map_or(d.air_density, |v| v.0),
                drag_coefficient: w.drag_coefficient.map_or(d.drag_coefficient, |v| v.0),
                gust: w.gust.map_or(0.0, |v| v.0),
                gust_frequency: w.gust_frequency.map_or(d.gust_frequency, |v| v.0),
            }),
        }
    }
}

/// A `[[cloth]]` table: grid, placement, fabric (a preset plus optional overrides), pins.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneCloth {
    /// Rows of particles.
    pub rows: Count,
    /// Columns of particles.
    pub cols: Count,
    /// Rest distance between neighbours, m.
    pub spacing: Positive,
    /// Position of particle (0, 0), m.
    #[serde(default = "default_origin")]
    pub origin: Vec3,
    /// Column direction (default +x).
    pub u: Option<Vec3>,
    /// Row direction (default -y: hanging; use [0, 0, 1] for a horizontal sheet).
    pub v: Option<Vec3>,
    /// Fabric preset: basic, cotton, wool, polyester (default basic).
    #[serde(default = "default_fabric")]
    pub fabric: String,
    /// Override: particle mass, kg.
    pub mass: Option<Positive>,
    /// Override: stretch compliance, m/N.
    pub stretch_compliance: Option<NonNegative>,
    /// Override: shear compliance, m/N.
    pub shear_compliance: Option<NonNegative>,
    /// Override: bending compliance, m/N.
    pub bend_compliance: Option<NonNegative>,
    /// Override: damping rate, 1/s.
    pub damping: Option<NonNegative>,
    /// Override: thickness, m.
    pub thickness: Option<NonNegative>,
    /// Pins (default none).
    #[serde(default)]
    pub pins: Vec<PinSpec>,
    /// Shear constraints (default on).
    #[serde(default = "yes")]
    pub shear: bool,
    /// Bending constraints (default on).
    #[serde(default = "yes")]
    pub bend: bool,
    /// Tether slack as a fraction of rest length; absent = 0.02 when there are pins,
    /// negative numbers are rejected; set `tethers = false` to disable.
    #[serde(default)]
    pub tethers: Option<TetherSetting>,
}

/// `tethers = false` or `tethers = 0.05`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(untagged)]
pub enum TetherSetting {
    /// On (`true`, default slack) or off (`false`).
    Switch(bool),
    /// On with this slack.
    Slack(NonNegative),
}

fn default_origin() -> Vec3 {
    Vec3([0.0, 1.0, 0.0])
}
fn default_fabric() -> String {
    "basic".into()
}
fn yes() -> bool {
    true
}

/// Tether slack when a scene names none.
pub const DEFAULT_TETHER_SLACK: f32 = 0.02;

impl SceneCloth {
    /// The cloth description.
    pub fn desc(&self) -> Result<ClothDesc> {
        let mut f = Fabric::preset(&self.fabric)?;
        let set = |o: Option<Positive>, f: &mut f32| {
            if let Some(v) = o {
                *f = v.0
            }
        };
        set(self.mass, &mut f.mass);
        let nn = |o: Option<NonNegative>, f: &mut f32| {
            if let Some(v) = o {
                *f = v.0
            }
        };
        nn(self.stretch_compliance, &mut f.stretch_compliance);
        nn(self.shear_compliance, &mut f.shear_compliance);
        nn(self.bend_compliance, &mut f.bend_compliance);
        nn(self.damping, &mut f.damping);
        nn(self.thickness, &mut f.thickness);
        let tethers = match &self.tethers {
            None | Some(TetherSetting::Switch(true)) => Some(DEFAULT_TETHER_SLACK),
            Some(TetherSetting::Switch(false)) => None,
            Some(TetherSetting::Slack(s)) => Some(s.0),
        };
        Ok(ClothDesc {
            rows: self.rows.0,
            cols: self.cols.0,
            spacing: self.spacing.0,
            origin: self.origin.0,
            u: self.u.map_or([1.0, 0.0, 0.0], |v| v.0),
            v: self.v.map_or([0.0, -1.0, 0.0], |v| v.0),
            fabric: f,
            pins: self.pins.clone(),
            shear: self.shear,
            bend: self.bend,
            tethers,
        })
    }
}

/// `[output]`: how long to run and what to write.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSection {
    /// Steps to run.
    #[serde(default = "default_steps")]
    pub steps: Count,
    /// Frames kept for the contact sheet / OBJ / GIF, spread evenly over the run.
    #[serde(default = "default_frames")]
    pub frames: Count,
    /// Write OBJ files of the frames.
    #[serde(default)]
    pub obj: bool,
    /// Write an animated GIF of the frames.
    #[serde(default)]
    pub gif: bool,
    /// Picture width, px.
    #[serde(default = "default_width")]
    pub width: Count,
    /// Picture height, px.
    #[serde(default = "default_height")]
    pub height: Count,
    /// Camera position (default: framed automatically).
    pub camera_eye: Option<Vec3>,
    /// Camera target (default: the scene's centre).
    pub camera_target: Option<Vec3>,
    /// How cloth is drawn: `"triangles"` (default) or `"nurbs"` (a NURBS surface over the
    /// particle grid).
    #[serde(default, skip_serializing_if = "ClothSurface::is_default")]
    pub cloth_surface: ClothSurface,
}

/// How pictures draw cloth.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ClothSurface {
    /// The simulation's own triangles.
    #[default]
    Triangles,
    /// A cubic NURBS surface whose control points are the particle grid (after the NURBS thesis on strands and surfaces).
    Nurbs,
}

impl ClothSurface {
    fn is_default(&self) -> bool {
        *self == ClothSurface::Triangles
    }
}

fn default_steps() -> Count {
    Count(300)
}
fn default_frames() -> Count {
    Count(6)
}
fn default_width() -> Count {
    Count(800)
}
fn default_height() -> Count {
    Count(600)
}

impl Default for OutputSection {
    fn default() -> Self {
        OutputSection {
            steps: default_steps(),
            frames: default_frames(),
            obj: false,
            gif: false,
            width: default_width(),
            height: default_height(),
            camera_eye: None,
            camera_target: None,
            cloth_surface: ClothSurface::Triangles,
        }
    }
}
