//! Typed errors. Every bad input a user can give becomes one of these, never a panic.

use thiserror::Error;

/// Result alias used across weft.
pub type Result<T, E = WeftError> = std::result::Result<T, E>;

/// Everything that can go wrong in weft, with a message a person understands.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum WeftError {
    /// A numeric or structural parameter is out of its allowed range.
    #[error("invalid parameter `{name}` = {value}: {reason}")]
    InvalidParameter {
        /// Parameter name as the user wrote it (scene key or API field).
        name: String,
        /// The offending value, printed.
        value: String,
        /// What the value must be.
        reason: String,
    },
    /// A triangle mesh cannot be used.
    #[error("invalid mesh{}: {reason}", source_name.as_ref().map(|s| format!(" `{s}`")).unwrap_or_default())]
    InvalidMesh {
        /// File name or mesh name, if known.
        source_name: Option<String>,
        /// What is wrong with it.
        reason: String,
    },
    /// A step produced a non-finite value; the state before the step was kept.
    #[error("step diverged: particle {particle} became non-finite in stage `{stage}`; the state before the step was kept")]
    Diverged {
        /// Index of the first particle found non-finite.
        particle: usize,
        /// The step stage that produced it.
        stage: &'static str,
    },
    /// A buffer given to the API has the wrong length.
    #[error("buffer `{name}` has length {got}, expected {expected}")]
    BufferLength {
        /// Buffer name.
        name: &'static str,
        /// Length given.
        got: usize,
        /// Length required.
        expected: usize,
    },
    /// An index given to the API is out of range.
    #[error("`{name}` index {index} is out of range (there are {len})")]
    IndexOutOfRange {
        /// What is indexed.
        name: &'static str,
        /// The index given.
        index: usize,
        /// How many there are.
        len: usize,
    },
    /// A scene file could not be read or understood.
    #[error("scene error: {0}")]
    Scene(String),
    /// File input or output failed.
    #[error("i/o error on `{path}`: {message}")]
    Io {
        /// The path involved.
        path: String,
        /// The operating system's message.
        message: String,
    },
}

impl WeftError {
    /// Shorthand for [`WeftError::InvalidParameter`].
    pub fn param(name: impl Into<String>, value: impl std::fmt::Display, reason: impl Into<String>) -> Self {
        WeftError::InvalidParameter {
            name: name.into(),
            value: value.to_string(),
            reason: reason.into(),
        }
    }

    /// Shorthand for [`WeftError::Io`].
    pub fn io(path: impl AsRef<std::path::Path>, e: std::io::Error) -> Self {
        WeftError::Io {
            path: path.as_ref().display().to_string(),
            message: e.to_string(),
        }
    }
}

/// Checks that `v` is finite, naming the parameter otherwise.
pub fn finite(name: &str, v: f32) -> Result<f32> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(WeftError::param(name, v, "must be a finite number"))
    }
}

/// Checks that `v` is finite and strictly positive.
pub fn positive(name: &str, v: f32) -> Result<f32> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(WeftError::param(name, v, "must be a finite number greater than zero"))
    }
}

/// Checks that `v` is a mass: finite and strictly positive, with a finite inverse (a
/// subnormal mass such as `1e-40` has an infinite inverse mass, which no step survives).
pub fn mass(name: &str, v: f32) -> Result<f32> {
    positive(name, v)?;
    if (1.0 / v).is_finite() {
        Ok(v)
    } else {
        Err(WeftError::param(
            name,
            v,
            format!("must be at least {:e} kg (its inverse must be finite)", 1.0 / f32::MAX),
        ))
    }
}

/// Checks that `v` is finite and not negative.
pub fn non_negative(name: &str, v: f32) -> Result<f32> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(WeftError::param(name, v, "must be a finite number, zero or greater"))
    }
}

/// Checks that every component of a vector is finite.
pub fn finite3(name: &str, v: [f32; 3]) -> Result<[f32; 3]> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(v)
    } else {
        Err(WeftError::param(name, format!("{v:?}"), "every component must be a finite number"))
    }
}
