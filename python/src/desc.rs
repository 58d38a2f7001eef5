//! Descriptions passed to a world: a cloth (`ClothDesc`), wind (`Wind`) and self-collision
//! settings (`SelfCollision`). Each is checked by the library when it is used; the names of
//! presets, responses and broadphases are the scene file's spellings.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use weft::model::fabric::Fabric;
use weft::model::self_collision::{Response, SelfBroadphase, SelfCollision};
use weft::{ClothDesc, PinSpec, Wind};

use crate::{bad_param, OrRaise};

/// A rectangular cloth: a `rows x cols` particle grid.
///
/// Particle `(r, c)` starts at `origin + c * spacing * u + r * spacing * v`. `fabric` is a
/// preset name (`weft.FABRIC_PRESETS`: basic, cotton, wool, polyester); `mass`,
/// `stretch_compliance`, `shear_compliance`, `bend_compliance`, `damping` and `thickness`
/// override the preset's values. `pins` is a list of pin specs, spelled as in a scene file:
/// `"first-row-corners"`, `{"row": r}`, `{"indices": [i, ...]}`, `{"cells": [(r, c), ...]}`,
/// `{"region": {"min": (x, y, z), "max": (x, y, z)}}`; omitted, the first row's two corners
/// are pinned, and `pins=[]` pins nothing. `tethers` is the slack of the long-range
/// attachments to the nearest pin (a fraction of the rest distance), or `None` for none.
#[pyclass(module = "weft", name = "ClothDesc", frozen)]
#[derive(Clone)]
pub struct PyClothDesc {
    pub(crate) desc: ClothDesc,
    fabric_name: String,
}

#[pymethods]
impl PyClothDesc {
    #[new]
    #[pyo3(signature = (
        rows = 20, cols = 20, spacing = 0.05, origin = [0.0, 1.0, 0.0], u = [1.0, 0.0, 0.0],
        v = [0.0, -1.0, 0.0], fabric = "basic", pins = None, *, shear = true, bend = true,
        tethers = Some(0.02), mass = None, stretch_compliance = None, shear_compliance = None,
        bend_compliance = None, damping = None, thickness = None
    ))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        rows: u32,
        cols: u32,
        spacing: f32,
        origin: [f32; 3],
        u: [f32; 3],
        v: [f32; 3],
        fabric: &str,
        pins: Option<&Bound<'_, PyAny>>,
        shear: bool,
        bend: bool,
        tethers: Option<f32>,
        mass: Option<f32>,
        stretch_compliance: Option<f32>,
        shear_compliance: Option<f32>,
        bend_compliance: Option<f32>,
        damping: Option<f32>,
        thickness: Option<f32>,
    ) -> PyResult<Self> {
        let mut f = Fabric::preset(fabric).or_raise()?;
        for (value, field) in [
            (mass, &mut f.mass),
            (stretch_compliance, &mut f.stretch_compliance),
            (shear_compliance, &mut f.shear_compliance),
            (bend_compliance, &mut f.bend_compliance),
            (damping, &mut f.damping),
            (thickness, &mut f.thickness),
        ] {
            if let Some(x) = value {
                *field = x;
            }
        }
        f.validate().or_raise()?;
        let pins = match pins {
            None => ClothDesc::default().pins,
            Some(p) => parse_pins(p)?,
        };
        let desc = ClothDesc {
            rows,
            cols,
            spacing,
            origin,
            u,
            v,
            fabric: f,
            pins,
            shear,
            bend,
            tethers,
        };
        // Grid size, spacing, directions and pin ranges are checked by `World.add_cloth`
        // (building the grid here as well would hold a large cloth twice).
        Ok(PyClothDesc {
            desc,
            fabric_name: fabric.to_owned(),
        })
    }

    /// Rows of particles.
    #[getter]
    fn rows(&self) -> u32 {
        self.desc.rows
    }

    /// Columns of particles.
    #[getter]
    fn cols(&self) -> u32 {
        self.desc.cols
    }

    /// Rest distance between grid neighbours, m.
    #[getter]
    fn spacing(&self) -> f32 {
        self.desc.spacing
    }

    /// Number of particles the cloth adds (`rows * cols`).
    #[getter]
    fn particle_count(&self) -> u64 {
        self.desc.rows as u64 * self.desc.cols as u64
    }

    /// The fabric preset the description started from.
    #[getter]
    fn fabric(&self) -> &str {
        &self.fabric_name
    }

    fn __repr__(&self) -> String {
        format!(
            "ClothDesc(rows={}, cols={}, spacing={}, origin={:?}, fabric={:?}, pins={})",
            self.desc.rows,
            self.desc.cols,
            self.desc.spacing,
            self.desc.origin,
            self.fabric_name,
            self.desc.pins.len()
        )
    }
}

fn pin_error(p: &Bound<'_, PyAny>, reason: &str) -> PyErr {
    let shown = p.repr().map(|r| r.to_string()).unwrap_or_else(|_| "?".into());
    bad_param("pins", shown, reason)
}

const PIN_FORMS: &str = "each pin must be \"first-row-corners\", {\"row\": r}, {\"indices\": [...]}, \
                         {\"cells\": [(r, c), ...]} or {\"region\": {\"min\": (x, y, z), \"max\": (x, y, z)}}";

/// The pin list of a `ClothDesc` (see its docs for the forms).
fn parse_pins(pins: &Bound<'_, PyAny>) -> PyResult<Vec<PinSpec>> {
    if pins.is_instance_of::<PyString>() || pins.is_instance_of::<PyDict>() {
        // A single spec where a list was meant.
        return Ok(vec![parse_pin(pins)?]);
    }
    let items = pins.try_iter().map_err(|_| pin_error(pins, "must be a list of pin specs"))?;
    let mut out = Vec::new();
    for item in items {
        out.push(parse_pin(&item?)?);
    }
    Ok(out)
}

fn parse_pin(p: &Bound<'_, PyAny>) -> PyResult<PinSpec> {
    if let Ok(s) = p.extract::<String>() {
        return match s.as_str() {
            "first-row-corners" => Ok(PinSpec::FirstRowCorners),
            _ => Err(pin_error(p, PIN_FORMS)),
        };
    }
    let d = p.cast::<PyDict>().map_err(|_| pin_error(p, PIN_FORMS))?;
    if d.len() != 1 {
        return Err(pin_error(p, PIN_FORMS));
    }
    let Some((key, value)) = d.iter().next() else {
        return Err(pin_error(p, PIN_FORMS));
    };
    let key: String = key.extract().map_err(|_| pin_error(p, PIN_FORMS))?;
    let wrong = |what: &str| pin_error(p, &format!("`{key}` needs {what}"));
    Ok(match key.as_str() {
        "row" => PinSpec::Row(value.extract().map_err(|_| wrong("a row number"))?),
        "indices" => PinSpec::Indices(value.extract().map_err(|_| wrong("a list of particle indices"))?),
        "cells" => PinSpec::Cells(value.extract().map_err(|_| wrong("a list of (row, col) pairs"))?),
        "region" => {
            let r = value
                .cast::<PyDict>()
                .map_err(|_| wrong("{\"min\": (x, y, z), \"max\": (x, y, z)}"))?;
            let corner = |name: &str| -> PyResult<[f32; 3]> {
                r.get_item(name)?
                    .ok_or_else(|| wrong("both `min` and `max`"))?
                    .extract()
                    .map_err(|_| wrong("`min` and `max` as three numbers each"))
            };
            PinSpec::Region {
                min: corner("min")?,
                max: corner("max")?,
            }
        }
        _ => return Err(pin_error(p, PIN_FORMS)),
    })
}

/// Wind acting on the cloth's triangles: mean air `velocity` (m/s), `air_density` (kg/m³),
/// `drag_coefficient`, relative `gust` amplitude (0 = steady) and `gust_frequency` (Hz).
#[pyclass(module = "weft", name = "Wind", frozen)]
#[derive(Clone)]
pub struct PyWind {
    pub(crate) wind: Wind,
}

#[pymethods]
impl PyWind {
    #[new]
    #[pyo3(signature = (velocity, *, air_density = 1.2, drag_coefficient = 1.0, gust = 0.0, gust_frequency = 0.5))]
    fn new(velocity: [f32; 3], air_density: f32, drag_coefficient: f32, gust: f32, gust_frequency: f32) -> PyResult<Self> {
        let wind = Wind {
            velocity,
            air_density,
            drag_coefficient,
            gust,
            gust_frequency,
        };
        // The library checks wind as part of the effects.
        weft::Effects {
            wind: Some(wind.clone()),
            ..Default::default()
        }
        .validate()
        .or_raise()?;
        Ok(PyWind { wind })
    }

    fn __repr__(&self) -> String {
        let w = &self.wind;
        format!(
            "Wind(velocity={:?}, air_density={}, drag_coefficient={}, gust={}, gust_frequency={})",
            w.velocity, w.air_density, w.drag_coefficient, w.gust, w.gust_frequency
        )
    }
}

/// Self-collision settings: collision `distance` in m (`None` = the smallest thickness or
/// spacing of the cloths), `friction` in [0, 1], `response` (`"vccpbd"`, `"pbd"` or
/// `"movement-speed"`), `broadphase` (`"hash"` or `"aabb-tree"`; both find the same pairs),
/// `measure` (record the percentage of particles in penetration after every step) and `travel`
/// (how far a particle may move in a step relative to the mean motion at most, in collision
/// distances, above 0 and at most 2; each particle uses what its velocity calls for, up to it:
/// lower is cheaper and clamps harder).
#[pyclass(module = "weft", name = "SelfCollision", frozen)]
#[derive(Clone)]
pub struct PySelfCollision {
    pub(crate) config: SelfCollision,
}

#[pymethods]
impl PySelfCollision {
    #[new]
    #[pyo3(signature = (*, distance = None, friction = 0.3, response = "vccpbd", broadphase = "hash", measure = false, travel = 1.0))]
    fn new(distance: Option<f32>, friction: f32, response: &str, broadphase: &str, measure: bool, travel: f32) -> PyResult<Self> {
        let responses = [Response::Vccpbd, Response::Pbd, Response::MovementSpeed];
        let response = responses
            .into_iter()
            .find(|r| r.name() == response)
            .ok_or_else(|| bad_param("self_collision.response", response, "expected one of vccpbd, pbd, movement-speed"))?;
        let broadphases = [SelfBroadphase::Hash, SelfBroadphase::AabbTree];
        let broadphase = broadphases
            .into_iter()
            .find(|b| b.name() == broadphase)
            .ok_or_else(|| bad_param("self_collision.broadphase", broadphase, "expected one of hash, aabb-tree"))?;
        let config = SelfCollision {
            distance,
            friction,
            response,
            broadphase,
            measure,
            travel,
        };
        // Checked now by the library's own check, on an empty world (which allocates nothing),
        // so a bad setting fails where it is written.
        let mut probe = weft::World::new(weft::SolverParams::default(), weft::Effects::default()).or_raise()?;
        probe.set_self_collision(Some(config.clone())).or_raise()?;
        Ok(PySelfCollision { config })
    }

    fn __repr__(&self) -> String {
        let c = &self.config;
        format!(
            "SelfCollision(distance={}, friction={}, response={:?}, broadphase={:?}, measure={}, travel={})",
            c.distance.map_or("None".to_string(), |d| d.to_string()),
            c.friction,
            c.response.name(),
            c.broadphase.name(),
            if c.measure { "True" } else { "False" },
            c.travel
        )
    }
}
