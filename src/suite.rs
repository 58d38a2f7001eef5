//! The self-collision benchmark suite: six scenes where cloth lies on cloth, so that the
//! stage is measured on piles, stacks, twists and flutter, not on one fold.
//!
//! Five scenes are scene files in `scenes/self-collision/` (`fold`, `pile`, `stacked`, `heap`,
//! `flag`); the sixth, `twist`, is built here because a scene file cannot move a pin: a strip
//! hanging from its top row whose bottom row is turned about the vertical axis (and slowly
//! raised) through [`World::set_kinematic_positions`] before every step, until the strip
//! wraps onto itself. [`SuiteRun`] loads either kind and steps it the same way.
//!
//! The audits of [`crate::self_collision::audit`] need each particle's rest position and
//! cloth: every suite cloth is a flat grid whose initial positions are its rest positions, so
//! [`SuiteRun`] keeps the positions it was built with.
//!
//! ```no_run
//! use weft::suite::SuiteRun;
//! let mut run = SuiteRun::load("scenes/self-collision".as_ref(), "twist", 1, true)?;
//! for _ in 0..10 {
//!     run.step()?;
//! }
//! println!("{} m", run.deepest_violation()?);
//! # Ok::<(), weft::WeftError>(())
//! ```

use std::path::Path;

use crate::error::{Result, WeftError};
use crate::model::fabric::Fabric;
use crate::scene::Scene;
use crate::self_collision::audit::{self, RestRule};
use crate::self_collision::{Response, SelfCollision, REST_SKIP_FACTOR};
use crate::{ClothDesc, Effects, PinSpec, SolverParams, World};

/// The suite's scenes, in the order the bench runs them.
pub const SCENES: [&str; 6] = ["fold", "pile", "stacked", "twist", "heap", "flag"];

/// The twist: rows and columns of the strip, spacing (= thickness), m.
const TWIST_ROWS: u32 = 100;
const TWIST_COLS: u32 = 40;
const TWIST_SPACING: f32 = 0.01;
/// Turn rate of the bottom row, rad/s (half a turn a second).
const TWIST_RATE: f32 = std::f32::consts::PI;
/// Rise of the bottom row, m/s, up to [`TWIST_RISE_MAX`].
const TWIST_RISE: f32 = 0.1;
const TWIST_RISE_MAX: f32 = 0.5;

/// The moving pins of the twist: the bottom row's indices and rest positions.
#[derive(Clone, Debug)]
struct Twist {
    indices: Vec<u32>,
    start: Vec<[f32; 3]>,
    targets: Vec<mint::Point3<f32>>,
}

/// One suite scene ready to step.
pub struct SuiteRun {
    /// The scene's name (one of [`SCENES`]).
    pub name: String,
    /// The world.
    pub world: World,
    /// Step length, s.
    pub dt: f32,
    /// Where the scene file puts the camera, if it does.
    pub camera_eye: Option<[f32; 3]>,
    /// What the camera looks at, if the scene file says.
    pub camera_target: Option<[f32; 3]>,
    twist: Option<Twist>,
    rest: [Vec<f32>; 3],
    group: Vec<u32>,
    /// Positions before the last step (for the crossing count).
    before: [Vec<f32>; 3],
}

/// The twist's world: a cotton strip of 100 x 40 particles at 1 cm (thickness 1 cm) hanging
/// from its top row 1.5 m up, its bottom row pinned too; PBD response, hash.
fn twist_world(threads: usize) -> Result<(World, Twist)> {
    let params = SolverParams {
        dt: 1.0 / 60.0,
        substeps: 10,
        iterations: 1,
        threads,
        ..Default::default()
    };
    let mut w = World::new(params, Effects::gravity())?;
    let fabric = Fabric {
        thickness: TWIST_SPACING,
        ..Fabric::preset("cotton")?
    };
    let half = 0.5 * (TWIST_COLS - 1) as f32 * TWIST_SPACING;
    let c = w.add_cloth(&ClothDesc {
        rows: TWIST_ROWS,
        cols: TWIST_COLS,
        spacing: TWIST_SPACING,
        origin: [-half, 1.5, 0.0],
        u: [1.0, 0.0, 0.0],
        v: [0.0, -1.0, 0.0],
        fabric,
        pins: vec![PinSpec::Row(0), PinSpec::Row(TWIST_ROWS - 1)],
        shear: true,
        bend: true,
        tethers: None,
    })?;
    w.set_self_collision(Some(SelfCollision {
        response: Response::Pbd,
        ..SelfCollision::default()
    }))?;
    let first = w.cloths()[c].first + (TWIST_ROWS - 1) * TWIST_COLS;
    let indices: Vec<u32> = (first..first + TWIST_COLS).collect();
    let start = indices.iter().map(|&i| w.particles().position(i as usize)).collect();
    Ok((
        w,
        Twist {
            indices,
            start,
            targets: Vec::new(),
        },
    ))
}

impl SuiteRun {
    /// Loads suite scene `name` (one of [`SCENES`]; the scene files are read from `dir`) on
    /// `threads` threads, with its self-collision settings when `self_collision` is true and
    /// without self-collision otherwise.
    pub fn load(dir: &Path, name: &str, threads: usize, self_collision: bool) -> Result<SuiteRun> {
        if !SCENES.contains(&name) {
            return Err(WeftError::param("scene", name, format!("expected one of {}", SCENES.join(", "))));
        }
        let threads16 = u16::try_from(threads).map_err(|_| WeftError::param("threads", threads, "at most 65535"))?;
        let (mut world, twist, eye, target) = if name == "twist" {
            let (w, t) = twist_world(threads)?;
            (w, Some(t), None, None)
        } else {
            let (mut scene, _) = Scene::load(&dir.join(format!("{name}.toml")))?;
            scene.solver.threads = threads16;
            let w = scene.world()?;
            let eye = scene.output.camera_eye.map(|v| v.0);
            let target = scene.output.camera_target.map(|v| v.0);
            (w, None, eye, target)
        };
        if !self_collision {
            world.set_self_collision(None)?;
        }
        let x = world.positions();
        let rest = x.map(|a| a.to_vec());
        let mut group = vec![u32::MAX; world.particle_count()];
        for (k, c) in world.cloths().iter().enumerate() {
            let end = (c.first + c.rows * c.cols) as usize;
            group[c.first as usize..end].fill(k as u32);
        }
        let dt = world.params().dt;
        Ok(SuiteRun {
            name: name.to_string(),
            world,
            dt,
            camera_eye: eye,
            camera_target: target,
            twist,
            before: rest.clone(),
            rest,
            group,
        })
    }

    /// One step: moves the twist's pins (if any) and steps the world by [`dt`](Self::dt).
    pub fn step(&mut self) -> Result<()> {
        self.prepare_step()?;
        self.world_step()
    }

    /// What [`step`](Self::step) does before the world steps: keeps the positions for
    /// [`crossings`](Self::crossings) and sets the twist's pin targets (not part of the step
    /// a bench times).
    pub fn prepare_step(&mut self) -> Result<()> {
        for (b, x) in self.before.iter_mut().zip(self.world.positions()) {
            b.clear();
            b.extend_from_slice(x);
        }
        if let Some(t) = &mut self.twist {
            let time = (self.world.time() + self.dt as f64) as f32;
            let (s, c) = (TWIST_RATE * time).sin_cos();
            let rise = (TWIST_RISE * time).min(TWIST_RISE_MAX);
            t.targets.clear();
            t.targets.extend(t.start.iter().map(|p| mint::Point3 {
                x: c * p[0] + s * p[2],
                y: p[1] + rise,
                z: -s * p[0] + c * p[2],
            }));
            self.world.set_kinematic_positions(&t.indices, &t.targets)?;
        }
        Ok(())
    }

    /// The world's step alone (after [`prepare_step`](Self::prepare_step)).
    pub fn world_step(&mut self) -> Result<()> {
        self.world.step(self.dt).map(|_| ())
    }

    /// The collision distance of the scene (its self-collision settings, or
    /// `min(thickness, spacing)` when they are off).
    pub fn distance(&self) -> f32 {
        self.world.self_collision_distance()
    }

    /// The pipeline's rest-distance rule: neighbours are particles of one cloth at most
    /// `REST_SKIP_FACTOR d` apart at rest.
    pub fn rest_rule(&self) -> Result<RestRule<'_>> {
        self.rest_rule_with(REST_SKIP_FACTOR * self.distance())
    }

    /// A rest-distance rule with another skip distance (the average-collision measure uses
    /// `1.5 d`).
    pub fn rest_rule_with(&self, skip: f32) -> Result<RestRule<'_>> {
        let r = &self.rest;
        RestRule::new([&r[0], &r[1], &r[2]], &self.group, skip)
    }

    /// The deepest violation of the collision distance between non-neighbours now, m.
    pub fn deepest_violation(&self) -> Result<f32> {
        audit::deepest_violation(self.world.positions(), &self.rest_rule()?, self.distance())
    }

    /// Layer crossings during the last step ([`audit::count_crossings`] between the positions
    /// before and after it, with a reach of twice the collision distance).
    pub fn crossings(&self) -> Result<usize> {
        let b = &self.before;
        audit::count_crossings(
            [&b[0], &b[1], &b[2]],
            self.world.positions(),
            self.world.triangles(),
            &self.rest_rule()?,
            2.0 * self.distance(),
        )
    }
}
