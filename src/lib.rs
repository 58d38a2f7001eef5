//! weft: cloth and hair as particles, fast.
pub mod collide;
pub mod error;
pub mod lanes;

pub use error::{Result, WeftError};
