//! weft: cloth and hair as particles, fast.
pub mod lanes;
