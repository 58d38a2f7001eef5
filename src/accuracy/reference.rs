//! The reference solution of a scene and its cache.
//!
//! The reference is the scene's cloth model integrated in f64 by the scalar XPBD step of
//! [`crate::reference`] with one iteration and `R` substeps per step. A second run at `R/2`
//! substeps gives `|x_R - x_{R/2}|`, which estimates the error of the `R` run and is stored as
//! [`Reference::self_error`] so reports can say how far the reference itself can be trusted.
//! Optionally ([`compute`](Reference::compute)'s `extrapolate`) the two are combined by
//! Richardson extrapolation, `x* = 2 x_R - x_{R/2}`: XPBD with one iteration is first order in
//! the substep, so this cancels the leading error term when the motion is smooth (the unit tests'
//! small cloth: errors fall to 6e-6 m against a 5e-5 m self-error). On cloth that vibrates in its
//! stiff modes the two runs differ mostly in those modes' phase, and extrapolating doubles that
//! difference instead (the extrapolated state's spring energy comes out visibly wrong), so
//! `weft accuracy` uses the plain `R` run.
//! All compliances of a scene are springs of stiffness `1/α` in the force-based methods, so both
//! sides integrate the same equations; constraints of zero compliance are rigid in the
//! reference and stiff springs in the force methods (see [`crate::integrate::mass_spring`]).
//!
//! **Scenes with obstacles or self-collision.** The f64 step has analytic obstacles (plane,
//! sphere, capsule, box, moving or not) and cloth self-collision ([`crate::reference`]), so
//! these scenes get the f64 reference too. Only what it lacks — triangle-mesh obstacles,
//! self-collision of strands — falls back to [`ReferenceKind::F32World`]: the world's own f32
//! XPBD step with `R` substeps and [`F32_REFERENCE_ITERATIONS`] iterations, and `R/2` for the
//! self-error. f32 caps `R`: a particle starting from rest moves `h² g` in its first substep,
//! and once that falls below half an ulp of its coordinate (6e-8 m at 1 m, reached near 150
//! substeps of 1/60 s) the prediction rounds back to `x` and the particle never starts moving.
//! `weft accuracy` therefore defaults to `R = 64` for these scenes, and such a reference is only
//! as good as its self-error says (on the drape and fold it was 2–3e-2 m).
//!
//! Cache file (`reference-<hash>.bin`, little endian): `b"WEFTREF1"`, the u64 key, u32 steps,
//! u32 particles, f64 self-error, then `steps + 1` frames of `3 n` f64 positions and one frame
//! of `3 n` f64 velocities. The key is an FNV-1a hash of the scene text and the settings, so
//! editing the scene or the settings computes a new reference.

use std::path::{Path, PathBuf};

use crate::error::{Result, WeftError};
use crate::model::params::{Method, SolverParams};
use crate::reference::ReferenceWorld;
use crate::World;

/// How a reference is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ReferenceKind {
    /// The scalar f64 XPBD step of [`crate::reference`], 1 iteration per substep.
    F64Xpbd,
    /// The world's f32 XPBD step with [`F32_REFERENCE_ITERATIONS`] iterations per substep
    /// (scenes with a feature the f64 step lacks: triangle-mesh obstacles, self-collision of
    /// strands; [`ReferenceWorld::missing_feature`]).
    F32World,
}

/// Iterations per substep of an [`ReferenceKind::F32World`] reference.
pub const F32_REFERENCE_ITERATIONS: u32 = 32;

impl ReferenceKind {
    /// The kind a world needs: [`F64Xpbd`](ReferenceKind::F64Xpbd) when the f64 step
    /// represents all of it, else [`F32World`](ReferenceKind::F32World).
    pub fn for_world(world: &World) -> ReferenceKind {
        match ReferenceWorld::new(&world.describe()).missing_feature() {
            None => ReferenceKind::F64Xpbd,
            Some(_) => ReferenceKind::F32World,
        }
    }

    /// A short description for report headers.
    pub fn describe(self) -> String {
        match self {
            ReferenceKind::F64Xpbd => "f64 scalar XPBD, 1 iteration".into(),
            ReferenceKind::F32World => {
                format!("f32 world XPBD, {F32_REFERENCE_ITERATIONS} iterations (the f64 step lacks a feature of the scene)")
            }
        }
    }
}

/// Positions of the reference at every step, and its final velocities.
#[derive(Clone, Debug, PartialEq)]
pub struct Reference {
    /// How it was computed.
    pub kind: ReferenceKind,
    /// Step length, s.
    pub dt: f32,
    /// Positions at step 0 (the initial state) to `steps`.
    pub frames: Vec<Vec<[f64; 3]>>,
    /// Velocities after the last step.
    pub final_velocity: Vec<[f64; 3]>,
    /// RMS over particles and steps of `|x_R - x_{R/2}|`, m: the error of the non-extrapolated
    /// run, an upper estimate of the reference's own error.
    pub self_error: f64,
}

/// 64-bit FNV-1a hash (stable across Rust versions, unlike `DefaultHasher`).
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes
        .iter()
        .fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3))
}

/// Builds a fresh world in the scene's initial state.
pub type MakeWorld<'a> = &'a dyn Fn() -> Result<World>;

/// Positions at every step and the final velocities.
type Trajectory = (Vec<Vec<[f64; 3]>>, Vec<[f64; 3]>);

fn run(make: MakeWorld<'_>, substeps: u32, steps: usize, kind: ReferenceKind) -> Result<Trajectory> {
    let mut w = make()?;
    let params = SolverParams {
        substeps,
        iterations: match kind {
            ReferenceKind::F64Xpbd => 1,
            ReferenceKind::F32World => F32_REFERENCE_ITERATIONS,
        },
        method: Method::Xpbd,
        backend: crate::model::params::Backend::Simd,
        guard: true,
        ..w.params().clone()
    };
    let dt = params.dt as f64;
    w.set_params(params)?;
    if kind == ReferenceKind::F32World {
        let state = |w: &World, v: bool| {
            let p = w.particles();
            (0..w.particle_count())
                .map(|i| if v { p.velocity(i) } else { p.position(i) }.map(f64::from))
                .collect::<Vec<_>>()
        };
        let mut frames = vec![state(&w, false)];
        for _ in 0..steps {
            w.step(dt as f32)?;
            frames.push(state(&w, false));
        }
        return Ok((frames, state(&w, true)));
    }
    let mut r = ReferenceWorld::new(&w.describe());
    let mut frames = vec![r.x.clone()];
    for _ in 0..steps {
        r.step(dt);
        if let Some(i) = r.x.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
            return Err(WeftError::Diverged {
                particle: i,
                stage: "reference",
            });
        }
        frames.push(r.x.clone());
    }
    Ok((frames, r.v))
}

impl Reference {
    /// Computes the reference for the world `make` builds (its topology, effects and initial
    /// state) over `steps` steps of its `dt`, with `substeps` (even, ≥ 2) substeps per step.
    pub fn compute(make: MakeWorld<'_>, steps: usize, substeps: u32, extrapolate: bool) -> Result<Reference> {
        if substeps < 2 || !substeps.is_multiple_of(2) {
            return Err(WeftError::param(
                "reference substeps",
                substeps,
                "must be an even number of at least 2",
            ));
        }
        let world = make()?;
        let (dt, kind) = (world.params().dt, ReferenceKind::for_world(&world));
        let (fine, v) = run(make, substeps, steps, kind)?;
        let (coarse, _) = run(make, substeps / 2, steps, kind)?;
        let mut sum = 0.0;
        let mut count = 0usize;
        let frames = fine
            .iter()
            .zip(&coarse)
            .map(|(f, c)| {
                f.iter()
                    .zip(c)
                    .map(|(a, b)| {
                        sum += (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>();
                        count += 1;
                        if extrapolate {
                            std::array::from_fn(|k| 2.0 * a[k] - b[k])
                        } else {
                            *a
                        }
                    })
                    .collect()
            })
            .collect();
        Ok(Reference {
            kind,
            dt,
            frames,
            final_velocity: v,
            self_error: (sum / count.max(1) as f64).sqrt(),
        })
    }

    /// Loads the reference from `dir/reference-<key>.bin` if present and matching, else
    /// computes it and writes the file. Returns the reference and whether it came from the cache.
    /// The key names the reference's version (`v3`: the self-collision travel of each step),
    /// raised whenever what the reference computes changes, so an older file is not read.
    pub fn cached(
        make: MakeWorld<'_>,
        key_text: &str,
        steps: usize,
        substeps: u32,
        extrapolate: bool,
        dir: &Path,
    ) -> Result<(Reference, bool)> {
        let world = make()?;
        let kind = ReferenceKind::for_world(&world);
        let key = fnv1a(
            format!("{key_text}\n--reference v3 steps={steps} substeps={substeps} extrapolate={extrapolate} kind={kind:?}").as_bytes(),
        );
        let path = Self::path(dir, key);
        let expected = (steps as u64 + 2) * world.particle_count() as u64 * 24 + 32;
        if let Ok(bytes) = crate::files::read_limited(&path, expected, "cached reference") {
            if let Some(r) = Self::decode(&bytes, key, world.particle_count(), steps, world.params().dt, kind) {
                return Ok((r, true));
            }
        }
        let r = Self::compute(make, steps, substeps, extrapolate)?;
        std::fs::create_dir_all(dir).map_err(|e| WeftError::io(dir, e))?;
        std::fs::write(&path, r.encode(key)).map_err(|e| WeftError::io(&path, e))?;
        Ok((r, false))
    }

    /// The cache file for `key` in `dir`.
    pub fn path(dir: &Path, key: u64) -> PathBuf {
        dir.join(format!("reference-{key:016x}.bin"))
    }

    fn encode(&self, key: u64) -> Vec<u8> {
        let n = self.final_velocity.len();
        let mut out = Vec::with_capacity(32 + (self.frames.len() + 1) * n * 24);
        out.extend_from_slice(b"WEFTREF1");
        out.extend_from_slice(&key.to_le_bytes());
        out.extend_from_slice(&((self.frames.len() - 1) as u32).to_le_bytes());
        out.extend_from_slice(&(n as u32).to_le_bytes());
        out.extend_from_slice(&self.self_error.to_le_bytes());
        for f in self.frames.iter().chain(std::iter::once(&self.final_velocity)) {
            for v in f.iter().flatten() {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        out
    }

    fn decode(b: &[u8], key: u64, n: usize, steps: usize, dt: f32, kind: ReferenceKind) -> Option<Reference> {
        let u32_at = |o: usize| Some(u32::from_le_bytes(b.get(o..o + 4)?.try_into().ok()?));
        let f64_at = |o: usize| Some(f64::from_le_bytes(b.get(o..o + 8)?.try_into().ok()?));
        if b.get(..8)? != b"WEFTREF1" || u64::from_le_bytes(b.get(8..16)?.try_into().ok()?) != key {
            return None;
        }
        if u32_at(16)? as usize != steps || u32_at(20)? as usize != n || b.len() != 32 + (steps + 2) * n * 24 {
            return None;
        }
        let self_error = f64_at(24)?;
        let mut frames = Vec::with_capacity(steps + 2);
        let mut o = 32;
        for _ in 0..steps + 2 {
            let mut f = Vec::with_capacity(n);
            for _ in 0..n {
                f.push([f64_at(o)?, f64_at(o + 8)?, f64_at(o + 16)?]);
                o += 24;
            }
            frames.push(f);
        }
        let final_velocity = frames.pop()?;
        Some(Reference {
            kind,
            dt,
            frames,
            final_velocity,
            self_error,
        })
    }
}
