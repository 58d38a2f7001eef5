//! A world as plain data: its state, topology and settings, taken by `World::describe`.
//!
//! This is what an independent reader of a world needs: the f64 reference step
//! (`crate::reference`) is built from a description and never sees the world's internals.

use crate::model::cloth::Tether;
use crate::model::effects::Effects;
use crate::model::layout::{ClothInfo, ScalpRange, StrandInfo};
use crate::model::self_collision::SelfCollision;
use crate::model::shapes::Shape;

/// One distance constraint.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistanceDesc {
    /// First particle.
    pub a: u32,
    /// Second particle.
    pub b: u32,
    /// Rest length, m.
    pub rest: f32,
    /// Compliance, m/N.
    pub compliance: f32,
}

/// One obstacle: an analytic shape (its pose at time 0) moving at a constant velocity, or a
/// triangle mesh (`shape: None`; a description does not carry the mesh).
#[derive(Clone, Debug, PartialEq)]
pub struct ObstacleDesc {
    /// The shape at time 0, `None` for a triangle mesh.
    pub shape: Option<Shape>,
    /// Velocity, m/s.
    pub velocity: [f32; 3],
    /// Friction coefficient, `None` = the world's default.
    pub friction: Option<f32>,
}

/// A world's state, topology and settings.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldDescription {
    /// Positions of the real particles, m.
    pub positions: Vec<[f32; 3]>,
    /// Velocities, m/s.
    pub velocities: Vec<[f32; 3]>,
    /// Inverse masses, 1/kg (0 = pinned).
    pub inv_mass: Vec<f32>,
    /// Fabric damping rate per particle, 1/s.
    pub damping: Vec<f32>,
    /// Distance constraints in the solver's colour order (within a colour no particle twice).
    pub colours: Vec<Vec<DistanceDesc>>,
    /// Tethers.
    pub tethers: Vec<Tether>,
    /// Cloth triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Wind drag area per particle of strands, m² (empty without strands).
    pub strand_area: Vec<f32>,
    /// Scalp collision ranges.
    pub scalps: Vec<ScalpRange>,
    /// Cloths.
    pub cloths: Vec<ClothInfo>,
    /// Strand groups.
    pub strands: Vec<StrandInfo>,
    /// Gravity, wind, drag.
    pub effects: Effects,
    /// Obstacles.
    pub obstacles: Vec<ObstacleDesc>,
    /// Default obstacle friction.
    pub friction: f32,
    /// Self-collision settings, if on.
    pub self_collision: Option<SelfCollision>,
    /// The collision distance in use, m.
    pub self_collision_distance: f32,
    /// Substeps per step.
    pub substeps: u32,
    /// Solver sweeps per substep.
    pub iterations: u32,
    /// The integration method.
    pub method: crate::model::params::Method,
    /// Simulated time, s.
    pub time: f64,
}
