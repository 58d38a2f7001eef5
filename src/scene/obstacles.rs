//! `[[obstacle]]` tables: analytic shapes and triangle meshes.
//!
//! ```toml
//! [[obstacle]]
//! kind = "sphere"            # plane | sphere | capsule | box | mesh
//! center = [0.0, 0.5, 0.0]
//! radius = 0.3
//! velocity = [0.0, 0.0, 0.1] # optional, m/s (default static)
//! friction = 0.4             # optional, else [effects] friction, else 0
//!
//! [[obstacle]]
//! kind = "mesh"
//! dress_form = 4800          # or obj = "path/to/mesh.obj" (relative to the working directory)
//! offset = [0.0, 0.0, 0.0]   # applied after scale
//! scale = 1.0
//! broadphase = "grid"        # grid (default) | bvh | hash
//! cells = [15, 30, 15]       # grid only; default: sized from the faces
//! face_memory = true
//! ```
//!
//! Plane: `point`, `normal`. Capsule: `a`, `b`, `radius`. Box: `center`, `half_extents`,
//! optional `rotation` (degrees about x, then y, then z). A key that does not apply to the kind
//! is an error, like an unknown key.

use serde::{Deserialize, Serialize};

use super::checked::{Count, NonNegative, Positive, Vec3};
use crate::error::{Result, WeftError};
use crate::model::shapes::Shape;
use crate::obstacles::mesh::dressform::dress_form;
use crate::obstacles::mesh::TriMesh;
use crate::obstacles::{BroadphaseKind, Obstacle};

/// Obstacle kinds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ObstacleKindName {
    /// A solid half-space.
    Plane,
    /// A ball.
    Sphere,
    /// A capsule.
    Capsule,
    /// A box.
    Box,
    /// A triangle mesh.
    Mesh,
}

/// Mesh broadphases.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BroadphaseName {
    /// The paper's uniform grid.
    Grid,
    /// AABB tree.
    Bvh,
    /// Spatial hash.
    Hash,
}

/// An `[[obstacle]]` table (module doc).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneObstacle {
    /// What it is.
    pub kind: ObstacleKindName,
    /// Sphere or box centre.
    pub center: Option<Vec3>,
    /// Sphere or capsule radius, m.
    pub radius: Option<Positive>,
    /// A point of a plane.
    pub point: Option<Vec3>,
    /// A plane's outward normal (normalised).
    pub normal: Option<Vec3>,
    /// Capsule axis start.
    pub a: Option<Vec3>,
    /// Capsule axis end.
    pub b: Option<Vec3>,
    /// Box half extents, m.
    pub half_extents: Option<[Positive; 3]>,
    /// Box rotation, degrees about x, y, z.
    pub rotation: Option<Vec3>,
    /// Mesh from an OBJ file.
    pub obj: Option<String>,
    /// Mesh: the procedural dress form with about this many faces.
    pub dress_form: Option<Count>,
    /// Mesh translation (after scaling), m.
    pub offset: Option<Vec3>,
    /// Mesh scale about the origin.
    pub scale: Option<Positive>,
    /// Mesh broadphase.
    pub broadphase: Option<BroadphaseName>,
    /// Grid cells per axis.
    pub cells: Option<[Count; 3]>,
    /// The paper's face memory (mesh only).
    pub face_memory: Option<bool>,
    /// Constant velocity, m/s.
    pub velocity: Option<Vec3>,
    /// Own Coulomb friction coefficient.
    pub friction: Option<NonNegative>,
}

fn need<T: Copy>(v: Option<T>, key: &str, kind: &str) -> Result<T> {
    v.ok_or_else(|| WeftError::Scene(format!("a {kind} obstacle needs `{key}`")))
}

impl SceneObstacle {
    /// Keys given that the kind does not use.
    fn stray_keys(&self) -> Vec<&'static str> {
        let given: [(&str, bool); 15] = [
            ("center", self.center.is_some()),
            ("radius", self.radius.is_some()),
            ("point", self.point.is_some()),
            ("normal", self.normal.is_some()),
            ("a", self.a.is_some()),
            ("b", self.b.is_some()),
            ("half_extents", self.half_extents.is_some()),
            ("rotation", self.rotation.is_some()),
            ("obj", self.obj.is_some()),
            ("dress_form", self.dress_form.is_some()),
            ("offset", self.offset.is_some()),
            ("scale", self.scale.is_some()),
            ("broadphase", self.broadphase.is_some()),
            ("cells", self.cells.is_some()),
            ("face_memory", self.face_memory.is_some()),
        ];
        let allowed: &[&str] = match self.kind {
            ObstacleKindName::Plane => &["point", "normal"],
            ObstacleKindName::Sphere => &["center", "radius"],
            ObstacleKindName::Capsule => &["a", "b", "radius"],
            ObstacleKindName::Box => &["center", "half_extents", "rotation"],
            ObstacleKindName::Mesh => &["obj", "dress_form", "offset", "scale", "broadphase", "cells", "face_memory"],
        };
        given
            .iter()
            .filter(|(k, on)| *on && !allowed.contains(k))
            .map(|(k, _)| *k)
            .collect()
    }

    /// The obstacle this table describes (meshes are built or loaded here).
    pub fn obstacle(&self) -> Result<Obstacle> {
        let kind = format!("{:?}", self.kind).to_lowercase();
        if let Some(k) = self.stray_keys().first() {
            return Err(WeftError::Scene(format!("`{k}` does not apply to a {kind} obstacle")));
        }
        let o = match self.kind {
            ObstacleKindName::Plane => Obstacle::shape(Shape::plane(
                need(self.point, "point", &kind)?.0,
                need(self.normal, "normal", &kind)?.0,
            )?)?,
            ObstacleKindName::Sphere => Obstacle::shape(Shape::Sphere {
                center: need(self.center, "center", &kind)?.0,
                radius: need(self.radius, "radius", &kind)?.0,
            })?,
            ObstacleKindName::Capsule => Obstacle::shape(Shape::Capsule {
                a: need(self.a, "a", &kind)?.0,
                b: need(self.b, "b", &kind)?.0,
                radius: need(self.radius, "radius", &kind)?.0,
            })?,
            ObstacleKindName::Box => Obstacle::shape(Shape::Box {
                center: need(self.center, "center", &kind)?.0,
                half: need(self.half_extents, "half_extents", &kind)?.map(|h| h.0),
                axes: Shape::axes_from_euler_deg(self.rotation.map_or([0.0; 3], |r| r.0)),
            })?,
            ObstacleKindName::Mesh => self.mesh()?,
        };
        let o = match self.velocity {
            Some(v) => o.with_velocity(v.0)?,
            None => o,
        };
        match self.friction {
            Some(f) => o.with_friction(f.0),
            None => Ok(o),
        }
    }

    fn mesh(&self) -> Result<Obstacle> {
        let base = match (&self.obj, self.dress_form) {
            (Some(path), None) => TriMesh::from_obj(path)?.0,
            (None, Some(faces)) => dress_form(faces.0 as usize)?,
            _ => {
                return Err(WeftError::Scene(
                    "a mesh obstacle needs exactly one of `obj` and `dress_form`".into(),
                ))
            }
        };
        let (s, d) = (self.scale.map_or(1.0, |s| s.0), self.offset.map_or([0.0; 3], |o| o.0));
        let mesh = if s == 1.0 && d == [0.0; 3] {
            base
        } else {
            let v = base.vertices().iter().map(|v| [0, 1, 2].map(|k| v[k] * s + d[k])).collect();
            TriMesh::new(v, base.faces().to_vec())?.0
        };
        let bp = match (self.broadphase.unwrap_or(BroadphaseName::Grid), self.cells) {
            (BroadphaseName::Grid, cells) => BroadphaseKind::Grid(cells.map(|c| c.map(|n| n.0 as usize))),
            (_, Some(_)) => return Err(WeftError::Scene("`cells` applies to the grid broadphase only".into())),
            (BroadphaseName::Bvh, None) => BroadphaseKind::Bvh,
            (BroadphaseName::Hash, None) => BroadphaseKind::Hash,
        };
        Obstacle::mesh(mesh, bp, self.face_memory.unwrap_or(false))
    }
}
