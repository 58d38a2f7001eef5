//! An obstacle of the world: its geometry (an analytic [`Shape`] or a triangle mesh with its
//! broadphase, face memories and kept candidate lists), its constant velocity and its own
//! friction coefficient (Landovskaya, Landovsky & Frolovsky). The step's stages live in
//! [`obstacles`](crate::obstacles).
//!
//! A moving obstacle's place is a function of time, `start + u t` (`displacement`), never an
//! accumulated sum, so a resumed run sees the same bits. A mesh is placed by translating the
//! base mesh and rebuilding its broadphase (or refitting it, for a BVH); a translation that
//! would overflow `f32` leaves the obstacle where it was.

use crate::error::{finite3, non_negative, Result};
use crate::model::shapes::Shape;
use crate::obstacles::mesh::broadphase::FaceBroadphase;
use crate::obstacles::mesh::contact::{BroadphaseKind, MeshBroadphase};
use crate::obstacles::mesh::face_cache::FaceCache;
use crate::obstacles::mesh::TriMesh;

/// A triangle-mesh obstacle.
#[derive(Debug, Clone)]
pub struct MeshObstacle {
    base: TriMesh,
    pub(crate) mesh: TriMesh,
    kind: BroadphaseKind,
    pub(crate) broadphase: MeshBroadphase,
    pub(crate) face_memory: bool,
    /// Face memory per particle (empty without face memory).
    pub(crate) memory: Vec<u32>,
    /// Kept candidate faces per particle.
    pub(crate) cache: FaceCache,
    placed: [f32; 3],
}

impl MeshObstacle {
    /// The mesh at its current place.
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }
    /// The broadphase in use.
    pub fn broadphase(&self) -> &MeshBroadphase {
        &self.broadphase
    }
    /// Whether the paper's face memory is on.
    pub fn face_memory(&self) -> bool {
        self.face_memory
    }
    /// Puts the mesh at `base + d` (module doc).
    pub(crate) fn place(&mut self, d: [f32; 3]) {
        if d == self.placed {
            return;
        }
        let mut m = self.base.clone();
        // A translation that would overflow f32 leaves the obstacle where it was.
        if m.translate(d).is_ok() {
            let bp = match (&mut self.broadphase, self.kind) {
                (MeshBroadphase::Bvh(b), _) => b.refit(&m).map(|_| None),
                (_, kind) => MeshBroadphase::build(kind, &m).map(Some),
            };
            if let Ok(bp) = bp {
                if let Some(bp) = bp {
                    self.broadphase = bp;
                }
                self.mesh = m;
                self.placed = d;
            }
        }
    }
}

/// What an obstacle is.
#[derive(Debug, Clone)]
pub enum Geometry {
    /// An analytic shape (at time 0).
    Shape(Shape),
    /// A triangle mesh.
    Mesh(Box<MeshObstacle>),
}

/// An obstacle: geometry, constant velocity, optional own friction coefficient.
#[derive(Debug, Clone)]
pub struct Obstacle {
    pub(crate) geometry: Geometry,
    pub(crate) velocity: [f32; 3],
    pub(crate) friction: Option<f32>,
}

impl Obstacle {
    /// An analytic obstacle (validated).
    pub fn shape(shape: Shape) -> Result<Obstacle> {
        shape.validate()?;
        Ok(Obstacle {
            geometry: Geometry::Shape(shape),
            velocity: [0.0; 3],
            friction: None,
        })
    }

    /// A mesh obstacle with the given broadphase and, optionally, the paper's face memory.
    pub fn mesh(mesh: TriMesh, broadphase: BroadphaseKind, face_memory: bool) -> Result<Obstacle> {
        let bp = MeshBroadphase::build(broadphase, &mesh)?;
        Ok(Obstacle {
            geometry: Geometry::Mesh(Box::new(MeshObstacle {
                base: mesh.clone(),
                mesh,
                kind: broadphase,
                broadphase: bp,
                face_memory,
                memory: Vec::new(),
                cache: FaceCache::default(),
                placed: [0.0; 3],
            })),
            velocity: [0.0; 3],
            friction: None,
        })
    }

    /// The same obstacle moving with constant velocity `v` (m/s) from time 0.
    pub fn with_velocity(mut self, v: [f32; 3]) -> Result<Obstacle> {
        finite3("obstacle.velocity", v)?;
        self.velocity = v;
        Ok(self)
    }

    /// The same obstacle with its own Coulomb friction coefficient (>= 0).
    pub fn with_friction(mut self, mu: f32) -> Result<Obstacle> {
        non_negative("obstacle.friction", mu)?;
        self.friction = Some(mu);
        Ok(self)
    }

    /// Geometry (meshes at their current place, shapes at time 0).
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }
    /// Velocity, m/s.
    pub fn velocity(&self) -> [f32; 3] {
        self.velocity
    }
    /// Own friction coefficient, if any.
    pub fn friction(&self) -> Option<f32> {
        self.friction
    }
    /// The analytic shape at time `t`, if this is one.
    pub fn shape_at(&self, t: f64) -> Option<Shape> {
        match &self.geometry {
            Geometry::Shape(s) => Some(s.translated(displacement(self.velocity, t))),
            Geometry::Mesh(_) => None,
        }
    }
    /// One line for reports: kind, size, broadphase.
    pub fn describe(&self) -> String {
        let v = if self.velocity == [0.0; 3] {
            String::from("static")
        } else {
            format!("moving {:?} m/s", self.velocity)
        };
        let what = match &self.geometry {
            Geometry::Shape(Shape::Plane { point, normal }) => format!("plane through {point:?}, normal {normal:?}"),
            Geometry::Shape(Shape::Sphere { center, radius }) => format!("sphere at {center:?}, radius {radius}"),
            Geometry::Shape(Shape::Capsule { a, b, radius }) => format!("capsule {a:?} - {b:?}, radius {radius}"),
            Geometry::Shape(Shape::Box { center, half, .. }) => format!("box at {center:?}, half extents {half:?}"),
            Geometry::Mesh(m) => format!(
                "mesh of {} faces, {}{}",
                m.mesh.face_count(),
                m.broadphase.describe(),
                if m.face_memory { ", face memory" } else { "" }
            ),
        };
        format!("{what}, {v}")
    }
}

/// The displacement `v t` of an obstacle moving with velocity `v` at time `t`.
pub(crate) fn displacement(v: [f32; 3], t: f64) -> [f32; 3] {
    v.map(|c| (c as f64 * t) as f32)
}
