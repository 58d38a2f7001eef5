//! `weft.World`: a simulated world, its obstacles, steps, read-back and snapshots.
//!
//! Read-back copies. The library keeps particles as structure of arrays (`x`, `y`, `z` each a
//! separate allocation, padded to the SIMD lane width), so an interleaved `(n, 3)` array cannot
//! be a view of them: its rows would need the three components one stride apart. Read-only
//! views of the three component arrays are not offered either: the step writes those arrays
//! with the interpreter lock released (another Python thread could read a view while it
//! changes, a data race), and adding a cloth reallocates them (a view would then point at freed
//! memory; NumPy keeps the owning object alive, not the buffer inside it). One copy per read is
//! cheap next to a step (12 bytes a particle); `out=` reuses the caller's array so that a
//! simulation loop allocates nothing.

use std::path::PathBuf;

use numpy::{AllowTypeChange, PyArray2, PyArrayLike2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyUserWarning;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use weft::model::shapes::Shape;
use weft::obstacles::mesh::TriMesh;
use weft::obstacles::{BroadphaseKind, Obstacle};
use weft::scene::Scene;
use weft::{Backend, Effects, Method, SolverParams, World};

use crate::desc::{PyClothDesc, PySelfCollision, PyWind};
use crate::{bad_param, OrRaise};

/// A simulated world: particles (cloths), obstacles and effects.
///
/// Keyword arguments give the solver settings (`dt`, `substeps`, `iterations`, `method`:
/// `"xpbd"`, `"symplectic-euler"`, `"leapfrog"` or `"implicit-euler"`, `stiffness`, `threads`:
/// 0 = all cores, `backend`: `"simd"` or `"scalar"`, `guard`) and the effects (`gravity`, a
/// 3-vector or `None`; `drag`; `wind`, a `weft.Wind`; `friction` against obstacles;
/// `self_collision`, a `weft.SelfCollision`). Results are the same bits for every `threads`
/// value and both backends.
#[pyclass(module = "weft", name = "World")]
pub struct PyWorld {
    world: World,
}

fn parse_method(name: &str) -> PyResult<Method> {
    Method::ALL.into_iter().find(|m| m.name() == name).ok_or_else(|| {
        bad_param(
            "solver.method",
            name,
            "expected one of xpbd, symplectic-euler, leapfrog, implicit-euler",
        )
    })
}

fn parse_backend(name: &str) -> PyResult<Backend> {
    match name {
        "simd" => Ok(Backend::Simd),
        "scalar" => Ok(Backend::Scalar),
        _ => Err(bad_param("solver.backend", name, "expected simd or scalar")),
    }
}

fn parse_broadphase(name: &str) -> PyResult<BroadphaseKind> {
    match name {
        "grid" => Ok(BroadphaseKind::Grid(None)),
        "bvh" => Ok(BroadphaseKind::Bvh),
        "hash" => Ok(BroadphaseKind::Hash),
        _ => Err(bad_param("mesh.broadphase", name, "expected grid, bvh or hash")),
    }
}

/// The caller's `out` array, or a new one of shape `shape`; `fill` writes its C-order data.
fn output<'py>(
    py: Python<'py>,
    name: &str,
    out: Option<&Bound<'py, PyAny>>,
    shape: [usize; 2],
    fill: impl FnOnce(&mut [f32]) -> PyResult<()>,
) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let need = || {
        format!(
            "must be a writeable C-contiguous float32 array of shape ({}, {})",
            shape[0], shape[1]
        )
    };
    let arr = match out {
        None => PyArray2::<f32>::zeros(py, shape, false),
        Some(o) => {
            let describe = || describe_array(o);
            let a = o.cast::<PyArray2<f32>>().map_err(|_| bad_param(name, describe(), need()))?;
            if a.shape() != shape || !a.is_c_contiguous() {
                return Err(bad_param(name, describe_array(o), need()));
            }
            a.clone()
        }
    };
    {
        let mut rw = arr
            .try_readwrite()
            .map_err(|e| bad_param(name, "array", format!("{}: {e}", need())))?;
        let s = rw
            .as_slice_mut()
            .map_err(|e| bad_param(name, "array", format!("{}: {e}", need())))?;
        fill(s)?;
    }
    Ok(arr)
}

/// `array of dtype float64 and shape (30, 3)`, or the type's name for anything else.
fn describe_array(o: &Bound<'_, PyAny>) -> String {
    let attr = |name: &str| o.getattr(name).and_then(|a| a.str()).map(|s| s.to_string());
    match (attr("dtype"), attr("shape")) {
        (Ok(d), Ok(s)) => format!("array of dtype {d} and shape {s}"),
        _ => o.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "object".into()),
    }
}

/// Interleaves three component slices into `out` (`3 n` floats).
fn interleave(src: [&[f32]; 3], out: &mut [f32]) {
    for (k, o) in out.chunks_exact_mut(3).enumerate() {
        o.copy_from_slice(&[src[0][k], src[1][k], src[2][k]]);
    }
}

/// Stacks three component slices as the rows of a `(3, n)` array.
fn stack(src: [&[f32]; 3], out: &mut [f32]) {
    let n = src[0].len();
    for (row, s) in out.chunks_exact_mut(n.max(1)).zip(src) {
        row.copy_from_slice(s);
    }
}

#[pymethods]
impl PyWorld {
    #[new]
    #[pyo3(signature = (
        *, dt = None, substeps = None, iterations = None, method = "xpbd", stiffness = None,
        threads = 0, backend = "simd", guard = true, gravity = Some([0.0, -9.81, 0.0]), drag = None,
        wind = None, friction = None, self_collision = None
    ))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        dt: Option<f32>,
        substeps: Option<u32>,
        iterations: Option<u32>,
        method: &str,
        stiffness: Option<f32>,
        threads: usize,
        backend: &str,
        guard: bool,
        gravity: Option<[f32; 3]>,
        drag: Option<f32>,
        wind: Option<PyRef<'_, PyWind>>,
        friction: Option<f32>,
        self_collision: Option<PyRef<'_, PySelfCollision>>,
    ) -> PyResult<Self> {
        let d = SolverParams::default();
        let params = SolverParams {
            dt: dt.unwrap_or(d.dt),
            substeps: substeps.unwrap_or(d.substeps),
            iterations: iterations.unwrap_or(d.iterations),
            method: parse_method(method)?,
            stiffness: stiffness.unwrap_or(d.stiffness),
            threads,
            backend: parse_backend(backend)?,
            guard,
        };
        let effects = Effects {
            gravity,
            wind: wind.map(|w| w.wind.clone()),
            drag,
        };
        let mut world = World::new(params, effects).or_raise()?;
        if let Some(mu) = friction {
            world.set_friction(mu).or_raise()?;
        }
        world.set_self_collision(self_collision.map(|s| s.config.clone())).or_raise()?;
        Ok(PyWorld { world })
    }

    /// The world a scene file describes (TOML, the format of `weft run`; see the scenes in the
    /// repository). Errors name the key, line and column.
    #[staticmethod]
    fn from_scene(path: PathBuf) -> PyResult<Self> {
        // The library's reader: a regular file within the scene size limit, UTF-8.
        let (scene, _) = Scene::load(&path).or_raise()?;
        Ok(PyWorld {
            world: scene.world().or_raise()?,
        })
    }

    /// The world described by scene text (the format of `World.from_scene`); `name` labels
    /// error messages.
    #[staticmethod]
    #[pyo3(signature = (text, name = "<scene>"))]
    fn from_scene_text(text: &str, name: &str) -> PyResult<Self> {
        let scene = Scene::parse(text, name).or_raise()?;
        Ok(PyWorld {
            world: scene.world().or_raise()?,
        })
    }

    /// Adds a cloth; returns its index.
    fn add_cloth(&mut self, desc: PyRef<'_, PyClothDesc>) -> PyResult<usize> {
        self.world.add_cloth(&desc.desc).or_raise()
    }

    /// Adds the solid half-space below the plane through `point` with outward `normal`
    /// (normalised here). `velocity` (m/s) moves it; `friction` is its own Coulomb
    /// coefficient. Returns the obstacle's index.
    #[pyo3(signature = (point, normal, *, velocity = None, friction = None))]
    fn add_plane(&mut self, point: [f32; 3], normal: [f32; 3], velocity: Option<[f32; 3]>, friction: Option<f32>) -> PyResult<usize> {
        let shape = Shape::plane(point, normal).or_raise()?;
        self.add_shape(shape, velocity, friction)
    }

    /// Adds a solid ball; see `add_plane` for `velocity` and `friction`.
    #[pyo3(signature = (center, radius, *, velocity = None, friction = None))]
    fn add_sphere(&mut self, center: [f32; 3], radius: f32, velocity: Option<[f32; 3]>, friction: Option<f32>) -> PyResult<usize> {
        self.add_shape(Shape::Sphere { center, radius }, velocity, friction)
    }

    /// Adds a capsule: all points within `radius` of the segment `a b`.
    #[pyo3(signature = (a, b, radius, *, velocity = None, friction = None))]
    fn add_capsule(&mut self, a: [f32; 3], b: [f32; 3], radius: f32, velocity: Option<[f32; 3]>, friction: Option<f32>) -> PyResult<usize> {
        self.add_shape(Shape::Capsule { a, b, radius }, velocity, friction)
    }

    /// Adds a solid box with half extents `half_extents`, rotated by `rotation` degrees about
    /// x, then y, then z (axis-aligned if omitted).
    #[pyo3(signature = (center, half_extents, *, rotation = None, velocity = None, friction = None))]
    fn add_box(
        &mut self,
        center: [f32; 3],
        half_extents: [f32; 3],
        rotation: Option<[f32; 3]>,
        velocity: Option<[f32; 3]>,
        friction: Option<f32>,
    ) -> PyResult<usize> {
        let axes = Shape::axes_from_euler_deg(rotation.unwrap_or([0.0; 3]));
        let shape = Shape::Box {
            center,
            half: half_extents,
            axes,
        };
        self.add_shape(shape, velocity, friction)
    }

    /// Adds a triangle mesh: `vertices` an `(m, 3)` array of positions, `faces` a `(k, 3)`
    /// array of vertex indices, counter-clockwise seen from outside. `broadphase` is `"grid"`,
    /// `"bvh"` or `"hash"`; `face_memory` keeps each particle's last face. Zero-area faces
    /// are dropped and, like open or inconsistently wound meshes, reported as a warning.
    #[pyo3(signature = (vertices, faces, *, broadphase = "grid", face_memory = false, velocity = None, friction = None))]
    #[allow(clippy::too_many_arguments)]
    fn add_mesh(
        &mut self,
        py: Python<'_>,
        vertices: PyArrayLike2<'_, f32, AllowTypeChange>,
        faces: PyArrayLike2<'_, i64, AllowTypeChange>,
        broadphase: &str,
        face_memory: bool,
        velocity: Option<[f32; 3]>,
        friction: Option<f32>,
    ) -> PyResult<usize> {
        let kind = parse_broadphase(broadphase)?;
        let (v, f) = (vertices.as_array(), faces.as_array());
        if v.ncols() != 3 {
            return Err(bad_param(
                "mesh.vertices",
                format!("array of shape {:?}", v.shape()),
                "must have shape (m, 3)",
            ));
        }
        if f.ncols() != 3 {
            return Err(bad_param(
                "mesh.faces",
                format!("array of shape {:?}", f.shape()),
                "must have shape (k, 3)",
            ));
        }
        let verts: Vec<[f32; 3]> = v.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect();
        let mut tris = Vec::with_capacity(f.nrows());
        for (i, r) in f.rows().into_iter().enumerate() {
            let mut t = [0u32; 3];
            for (slot, &k) in t.iter_mut().zip(r.iter()) {
                *slot = u32::try_from(k).map_err(|_| {
                    bad_param(
                        "mesh.faces",
                        format!("face {i} uses vertex {k}"),
                        "vertex indices must be between 0 and 2^32 - 1",
                    )
                })?;
            }
            tris.push(t);
        }
        let (mesh, report) = TriMesh::new(verts, tris).or_raise()?;
        for w in &report.warnings {
            let msg = std::ffi::CString::new(format!("weft mesh: {w}")).unwrap_or_default();
            PyErr::warn(py, &py.get_type::<PyUserWarning>(), &msg, 1)?;
        }
        let o = Obstacle::mesh(mesh, kind, face_memory).or_raise()?;
        self.add_obstacle(o, velocity, friction)
    }

    /// The number of obstacles added.
    #[getter]
    fn obstacle_count(&self) -> usize {
        self.world.obstacles().len()
    }

    /// Coulomb friction coefficient of obstacles that have none of their own.
    fn set_friction(&mut self, mu: f32) -> PyResult<()> {
        self.world.set_friction(mu).or_raise()
    }

    /// Turns self-collision on (a `weft.SelfCollision`) or off (`None`).
    fn set_self_collision(&mut self, config: Option<PyRef<'_, PySelfCollision>>) -> PyResult<()> {
        self.world.set_self_collision(config.map(|c| c.config.clone())).or_raise()
    }

    /// Steps that ran without self-collision because their pair lists could not be built (more
    /// than 128 pairs a particle on average: a cloth collapsed onto itself, or a distance far above the
    /// spacing). 0 while self-collision holds.
    #[getter]
    fn self_collision_failed_steps(&self) -> u64 {
        self.world.self_collision_stats().failed_steps
    }

    /// Whether self-collision is on.
    #[getter]
    fn self_collision(&self) -> bool {
        self.world.self_collision().is_some()
    }

    /// Sets gravity (a 3-vector, m/s²) or turns it off (`None`).
    fn set_gravity(&mut self, gravity: Option<[f32; 3]>) -> PyResult<()> {
        let e = Effects {
            gravity,
            ..self.world.effects().clone()
        };
        self.world.set_effects(e).or_raise()
    }

    /// Sets the wind (a `weft.Wind`) or turns it off (`None`).
    fn set_wind(&mut self, wind: Option<PyRef<'_, PyWind>>) -> PyResult<()> {
        let e = Effects {
            wind: wind.map(|w| w.wind.clone()),
            ..self.world.effects().clone()
        };
        self.world.set_effects(e).or_raise()
    }

    /// Advances the world by one step of `dt` seconds (default: the world's `dt`). Runs with the
    /// interpreter lock released. A step that diverges raises `weft.DivergedError` and leaves
    /// the state before it.
    #[pyo3(signature = (dt = None))]
    fn step(&mut self, py: Python<'_>, dt: Option<f32>) -> PyResult<()> {
        let world = &mut self.world;
        let dt = dt.unwrap_or(world.params().dt);
        py.detach(move || world.step(dt)).or_raise()
    }

    /// Adds `frame_dt` seconds of display time and takes the whole fixed steps of `dt` it owes
    /// (at most `max_steps_per_advance`, default 8). Returns an `AdvanceReport`; its `alpha`
    /// blends the last two states in `interpolated_positions`.
    fn advance(&mut self, py: Python<'_>, frame_dt: f64) -> PyResult<PyAdvanceReport> {
        let world = &mut self.world;
        let r = py.detach(move || world.advance(frame_dt)).or_raise()?;
        Ok(PyAdvanceReport {
            steps: r.steps,
            capped: r.capped,
            dropped_time: r.dropped_time,
            alpha: r.alpha,
        })
    }

    /// Sets the most fixed steps one `advance` call may take (at least 1).
    fn set_max_steps_per_advance(&mut self, max: u32) -> PyResult<()> {
        self.world.set_max_steps_per_advance(max).or_raise()
    }

    /// Positions as an `(n, 3)` float32 array: a new one, or written into `out` (which must
    /// be a C-contiguous float32 array of that shape) and returned.
    #[pyo3(signature = (out = None))]
    fn positions<'py>(&self, py: Python<'py>, out: Option<&Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let n = self.world.particle_count();
        output(py, "positions out", out, [n, 3], |s| {
            interleave(self.world.positions(), s);
            Ok(())
        })
    }

    /// Velocities (m/s) as an `(n, 3)` float32 array; `out` as for `positions`.
    #[pyo3(signature = (out = None))]
    fn velocities<'py>(&self, py: Python<'py>, out: Option<&Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let n = self.world.particle_count();
        output(py, "velocities out", out, [n, 3], |s| {
            interleave(self.world.velocities(), s);
            Ok(())
        })
    }

    /// Area-weighted unit vertex normals as an `(n, 3)` float32 array (zero for a particle in
    /// no triangle); `out` as for `positions`.
    #[pyo3(signature = (out = None))]
    fn normals<'py>(&self, py: Python<'py>, out: Option<&Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let n = self.world.particle_count();
        output(py, "normals out", out, [n, 3], |s| self.world.read_normals(s).or_raise())
    }

    /// Positions blended between the last two steps taken by `advance`,
    /// `x_prev + alpha (x - x_prev)`, as an `(n, 3)` float32 array; `out` as for `positions`.
    #[pyo3(signature = (alpha, out = None))]
    fn interpolated_positions<'py>(
        &self,
        py: Python<'py>,
        alpha: f32,
        out: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let n = self.world.particle_count();
        output(py, "interpolated positions out", out, [n, 3], |s| {
            self.world.interpolated_positions(alpha, s).or_raise()
        })
    }

    /// Positions as a `(3, n)` float32 array (rows x, y, z: the library's own layout, three
    /// contiguous copies); `out` as for `positions` with shape `(3, n)`.
    #[pyo3(signature = (out = None))]
    fn positions_soa<'py>(&self, py: Python<'py>, out: Option<&Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let n = self.world.particle_count();
        output(py, "positions_soa out", out, [3, n], |s| {
            stack(self.world.positions(), s);
            Ok(())
        })
    }

    /// Velocities as a `(3, n)` float32 array; see `positions_soa`.
    #[pyo3(signature = (out = None))]
    fn velocities_soa<'py>(&self, py: Python<'py>, out: Option<&Bound<'py, PyAny>>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let n = self.world.particle_count();
        output(py, "velocities_soa out", out, [3, n], |s| {
            stack(self.world.velocities(), s);
            Ok(())
        })
    }

    /// The cloths' triangles as a `(k, 3)` uint32 array of particle indices.
    fn triangles<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<u32>> {
        let t = self.world.triangles();
        let arr = PyArray2::<u32>::zeros(py, [t.len(), 3], false);
        if let Ok(mut rw) = arr.try_readwrite() {
            if let Ok(s) = rw.as_slice_mut() {
                s.copy_from_slice(t.as_flattened());
            }
        }
        arr
    }

    /// Moves pinned particle `i` to `position` over the next step (it travels in a straight
    /// line through the substeps).
    fn set_pin_position(&mut self, i: usize, position: [f32; 3]) -> PyResult<()> {
        self.world.set_pin_position(i, position.into()).or_raise()
    }

    /// A copy of the evolving state (positions, velocities, masses, time, steps, pending pin
    /// moves, the `advance` accumulator).
    fn snapshot(&self) -> PySnapshot {
        PySnapshot {
            snap: self.world.snapshot(),
        }
    }

    /// Puts the world back into the state of `snapshot`; the run then continues bit for bit as
    /// it did from there. Raises, changing nothing, if the particle counts differ.
    fn restore(&mut self, snapshot: PyRef<'_, PySnapshot>) -> PyResult<()> {
        self.world.restore_snapshot(&snapshot.snap).or_raise()
    }

    /// Back to the state before the first step since the last `add_cloth`.
    fn reset(&mut self) -> PyResult<()> {
        self.world.reset().or_raise()
    }

    /// Energy (J: kinetic, potential, elastic, total) and strain (max, mean) of the current
    /// state, as a dict.
    fn metrics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let m = self.world.metrics();
        let d = PyDict::new(py);
        for (k, v) in [
            ("kinetic", m.kinetic),
            ("potential", m.potential),
            ("elastic", m.elastic),
            ("total", m.total),
            ("max_strain", m.max_strain),
            ("mean_strain", m.mean_strain),
        ] {
            d.set_item(k, v)?;
        }
        Ok(d)
    }

    /// Number of particles.
    #[getter]
    fn particle_count(&self) -> usize {
        self.world.particle_count()
    }

    /// Simulated time, s.
    #[getter]
    fn time(&self) -> f64 {
        self.world.time()
    }

    /// Steps taken.
    #[getter]
    fn steps(&self) -> u64 {
        self.world.steps()
    }

    /// The fixed step length of `advance` and the default of `step`, s.
    #[getter]
    fn dt(&self) -> f32 {
        self.world.params().dt
    }

    /// Worker threads (0 = the global pool on all cores or the calling thread, whichever
    /// the world measures faster).
    #[getter]
    fn threads(&self) -> usize {
        self.world.params().threads
    }

    /// With `threads = 0`: where the last trial chose to run the steps, as a dict
    /// (`caller_thread`, and the shortest trial step in ms of each side, `pool_ms` and
    /// `caller_ms`); None for other thread settings and before the first trial has
    /// ended.
    #[getter]
    fn thread_choice<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(c) = self.world.thread_choice() else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        d.set_item("caller_thread", c.caller_thread)?;
        d.set_item("pool_ms", c.pool_ms)?;
        d.set_item("caller_ms", c.caller_ms)?;
        Ok(Some(d))
    }

    fn __len__(&self) -> usize {
        self.world.particle_count()
    }

    fn __repr__(&self) -> String {
        format!(
            "World(particles={}, cloths={}, obstacles={}, steps={}, time={})",
            self.world.particle_count(),
            self.world.cloths().len(),
            self.world.obstacles().len(),
            self.world.steps(),
            self.world.time()
        )
    }
}

impl PyWorld {
    fn add_shape(&mut self, shape: Shape, velocity: Option<[f32; 3]>, friction: Option<f32>) -> PyResult<usize> {
        let o = Obstacle::shape(shape).or_raise()?;
        self.add_obstacle(o, velocity, friction)
    }

    fn add_obstacle(&mut self, mut o: Obstacle, velocity: Option<[f32; 3]>, friction: Option<f32>) -> PyResult<usize> {
        if let Some(v) = velocity {
            o = o.with_velocity(v).or_raise()?;
        }
        if let Some(mu) = friction {
            o = o.with_friction(mu).or_raise()?;
        }
        self.world.add_obstacle(o).or_raise()
    }
}

/// What one `World.advance` call did: fixed `steps` taken, whether the cap was reached
/// (`capped`) and the simulated time dropped for it (`dropped_time`, s), and `alpha`, the
/// time owed past the last step as a fraction of `dt`.
#[pyclass(module = "weft", name = "AdvanceReport", frozen, get_all)]
#[derive(Clone)]
pub struct PyAdvanceReport {
    steps: u32,
    capped: bool,
    dropped_time: f64,
    alpha: f32,
}

#[pymethods]
impl PyAdvanceReport {
    fn __repr__(&self) -> String {
        format!(
            "AdvanceReport(steps={}, capped={}, dropped_time={}, alpha={})",
            self.steps,
            if self.capped { "True" } else { "False" },
            self.dropped_time,
            self.alpha
        )
    }
}

/// A copy of a world's evolving state, from `World.snapshot()`, for `World.restore`.
#[pyclass(module = "weft", name = "Snapshot", frozen)]
pub struct PySnapshot {
    snap: weft::Snapshot,
}

#[pymethods]
impl PySnapshot {
    /// Particles the snapshot holds.
    #[getter]
    fn particle_count(&self) -> usize {
        self.snap.particle_count()
    }

    /// Steps the world had taken.
    #[getter]
    fn steps(&self) -> u64 {
        self.snap.steps()
    }

    fn __repr__(&self) -> String {
        format!("Snapshot(particles={}, steps={})", self.snap.particle_count(), self.snap.steps())
    }
}
