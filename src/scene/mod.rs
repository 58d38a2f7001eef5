//! Scene files: a TOML description of what to simulate, read through serde.
//!
//! Every table refuses unknown keys; every number is range-checked as it is read, so an error
//! names the key, the line and the column. Cross-field problems found when the world is built
//! (a pin outside its grid, say) name the cloth and the line of its `[[cloth]]` table.
//!
//! ```toml
//! [solver]
//! dt = 0.016666
//! substeps = 10
//! iterations = 1
//!
//! [effects]
//! gravity = [0.0, -9.81, 0.0]
//!
//! [[cloth]]
//! rows = 30
//! cols = 30
//! spacing = 0.03
//! origin = [-0.45, 1.6, 0.0]
//! fabric = "cotton"
//! pins = ["first-row-corners"]
//!
//! [effects.self_collision]   # optional: particle–particle contacts
//! response = "vccpbd"         # or "pbd", "movement-speed"
//! broadphase = "hash"         # or "aabb-tree"
//! friction = 0.3
//! measure = false             # true: average collision over the steps (a query a step)
//! travel = 1.0                # most T / d a step, in (0, 2]: lower is cheaper, clamps harder
//!
//! [output]
//! steps = 300
//! ```
//!
//! RON is not supported: TOML covers the format, and one syntax keeps error messages uniform.

pub mod checked;
pub mod obstacles;
mod sections;
mod strands_section;

pub use sections::{
    ClothSurface, EffectsSection, OutputSection, SceneCloth, SelfCollisionSection, SolverSection, TetherSetting, WindSection,
};
pub use strands_section::{ScalpKind, SceneScalp, SceneStrands};

use crate::error::{Result, WeftError};
use crate::world::World;

/// A parsed scene.
#[derive(Clone, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Solver settings.
    #[serde(default)]
    pub solver: SolverSection,
    /// External effects; an effect not named is off and costs nothing.
    #[serde(default)]
    pub effects: EffectsSection,
    /// Cloth pieces.
    #[serde(default)]
    pub cloth: Vec<toml::Spanned<SceneCloth>>,
    /// Obstacles (see [`obstacles`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub obstacle: Vec<toml::Spanned<obstacles::SceneObstacle>>,
    /// Hair: strand groups on scalps.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub strands: Vec<toml::Spanned<SceneStrands>>,
    /// What a run writes.
    #[serde(default)]
    pub output: OutputSection,
}

/// Line and column (1-based) of a byte offset in `text`.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map(|l| l.chars().count()).unwrap_or(0) + 1;
    (line, col)
}

impl Scene {
    /// Parses scene text; `name` labels error messages (usually the file path).
    pub fn parse(text: &str, name: &str) -> Result<Scene> {
        let scene: Scene = toml::from_str(text).map_err(|e| {
            let at = e.span().map(|s| {
                let (l, c) = line_col(text, s.start);
                format!(" at line {l}, column {c}")
            });
            WeftError::Scene(format!("{name}{}: {}", at.unwrap_or_default(), e.message()))
        })?;
        scene.check(text, name)?;
        Ok(scene)
    }

    /// Reads and parses a scene file.
    pub fn load(path: &std::path::Path) -> Result<(Scene, String)> {
        let text = crate::files::read_text_limited(path, crate::files::SCENE_LIMIT, "scene")?;
        let scene = Scene::parse(&text, &path.display().to_string())?;
        Ok((scene, text))
    }

    /// Refuses a scene whose estimated memory exceeds the limit ([`crate::model::budget`]),
    /// then builds the world once to surface cross-field errors with the cloth's location.
    fn check(&self, text: &str, name: &str) -> Result<()> {
        self.memory_counts().check().map_err(|e| WeftError::Scene(format!("{name}: {e}")))?;
        self.build_world(Some((text, name))).map(|_| ())
    }

    /// The counts of the memory estimate, from the scene's sizes alone (no world is built,
    /// no mesh read; pieces whose description is invalid count as empty).
    pub fn memory_counts(&self) -> crate::model::budget::MemoryCounts {
        let mut c = crate::model::budget::MemoryCounts {
            obstacles: self.obstacle.len() as u64,
            wind: self.effects.wind.is_some(),
            self_collision: self.effects.self_collision.is_some(),
            force_method: self.solver.params().method != crate::model::params::Method::Xpbd,
            implicit: self.solver.params().method == crate::model::params::Method::ImplicitEuler,
            ..Default::default()
        };
        for cloth in &self.cloth {
            if let Ok(d) = cloth.get_ref().desc() {
                c = c.plus(&d.memory_counts());
            }
        }
        for s in &self.strands {
            if let Ok(d) = s.get_ref().desc() {
                c = c.plus(&d.memory_counts());
            }
        }
        c
    }

    /// The world this scene describes.
    pub fn world(&self) -> Result<World> {
        self.build_world(None)
    }

    fn build_world(&self, src: Option<(&str, &str)>) -> Result<World> {
        let mut world = World::new(self.solver.params(), self.effects.effects())?;
        let at = |span: std::ops::Range<usize>| {
            src.map(|(text, name)| {
                let (l, col) = line_col(text, span.start);
                format!("{name} at line {l}, column {col}: ")
            })
            .unwrap_or_default()
        };
        world.set_self_collision(self.effects.self_collision.as_ref().map(|s| s.config()))?;
        for (k, c) in self.cloth.iter().enumerate() {
            let desc = c.get_ref().desc().and_then(|d| world.add_cloth(&d).map(|_| ()));
            if let Err(e) = desc {
                return Err(WeftError::Scene(format!("{}cloth {k}: {e}", at(c.span()))));
            }
        }
        if let Some(mu) = self.effects.friction {
            world.set_friction(mu.0)?;
        }
        for (k, o) in self.obstacle.iter().enumerate() {
            if let Err(e) = o.get_ref().obstacle().and_then(|o| world.add_obstacle(o)) {
                return Err(WeftError::Scene(format!("{}obstacle {k}: {e}", at(o.span()))));
            }
        }
        for (k, s) in self.strands.iter().enumerate() {
            let added = s.get_ref().desc().and_then(|d| world.add_strands(&d).map(|_| ()));
            if let Err(e) = added {
                // A bad scalp is reported at the scalp table, anything else at the strands table.
                let scalp_err = s.get_ref().scalp.get_ref().scalp().is_err();
                let start = if scalp_err {
                    s.get_ref().scalp.span().start
                } else {
                    s.span().start
                };
                return Err(WeftError::Scene(format!("{}strands {k}: {e}", at(start..start))));
            }
        }
        Ok(world)
    }

    /// Serialises the scene back to TOML.
    pub fn to_toml(&self) -> Result<String> {
        toml::to_string(self).map_err(|e| WeftError::Scene(format!("cannot write the scene: {e}")))
    }
}

impl World {
    /// Builds the world a scene describes.
    pub fn from_scene(scene: &Scene) -> Result<World> {
        scene.world()
    }
}

#[cfg(test)]
mod tests;
