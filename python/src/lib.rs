//! Python bindings of weft: the module `weft` (PyO3, NumPy arrays).
//!
//! The classes wrap the library's types one to one: [`world::PyWorld`] owns a [`weft::World`],
//! [`desc::PyClothDesc`] builds a [`weft::ClothDesc`], and so on. Every error of the library
//! becomes the Python exception `weft.WeftError` (a `ValueError`) carrying the library's
//! message; a diverged step raises its subclass `weft.DivergedError`.
//!
//! The step and `advance` run with the interpreter lock released, so other Python threads run
//! meanwhile; the binding adds no allocation to a step. Read-back copies the library's
//! structure-of-arrays particles into NumPy arrays, new ones or the caller's (see
//! [`world`] for why a zero-copy view is not offered).

mod desc;
mod world;

use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

create_exception!(
    weft,
    WeftError,
    PyValueError,
    "An error of the weft library: a bad parameter, mesh, scene file or buffer, or a diverged step. The message names what was wrong."
);
create_exception!(
    weft,
    DivergedError,
    WeftError,
    "A step produced a non-finite value; the state before the step was kept."
);

/// The library's error as a Python exception with the library's message.
pub(crate) fn to_py(e: weft::WeftError) -> PyErr {
    match e {
        weft::WeftError::Diverged { .. } => DivergedError::new_err(e.to_string()),
        other => WeftError::new_err(other.to_string()),
    }
}

/// Result of a library call, as a Python result.
pub(crate) trait OrRaise<T> {
    /// Converts the library's error into `weft.WeftError`.
    fn or_raise(self) -> PyResult<T>;
}

impl<T> OrRaise<T> for weft::Result<T> {
    fn or_raise(self) -> PyResult<T> {
        self.map_err(to_py)
    }
}

/// An "invalid parameter" error in the library's wording.
pub(crate) fn bad_param(name: &str, value: impl std::fmt::Display, reason: impl Into<String>) -> PyErr {
    to_py(weft::WeftError::param(name, value, reason))
}

/// Fast, deterministic particle simulation of cloth and hair.
///
/// Build a `World`, add cloths (`ClothDesc`) and obstacles, step it, read positions,
/// velocities and normals as `(n, 3)` float32 NumPy arrays.
#[pymodule(name = "weft")]
fn weft_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("WeftError", py.get_type::<WeftError>())?;
    m.add("DivergedError", py.get_type::<DivergedError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("FABRIC_PRESETS", weft::model::fabric::PRESETS.to_vec())?;
    m.add_class::<world::PyWorld>()?;
    m.add_class::<world::PyAdvanceReport>()?;
    m.add_class::<world::PySnapshot>()?;
    m.add_class::<desc::PyClothDesc>()?;
    m.add_class::<desc::PyWind>()?;
    m.add_class::<desc::PySelfCollision>()?;
    Ok(())
}
