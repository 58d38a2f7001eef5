//! weft: cloth and hair as particles, fast.
pub mod error;
pub mod lanes;
pub mod strands;

pub use error::{Result, WeftError};
