#![doc = include_str!("../README.md")]
#![warn(missing_docs)]
pub mod accuracy;
#[cfg(feature = "capi")]
pub mod capi;
pub mod checkpoint;
pub mod cloth;
pub mod collide;
pub mod constraints;
pub mod effects;
pub mod embed;
pub mod error;
pub mod export;
pub mod fabric;
#[doc(hidden)]
pub mod fuzzing;
pub mod integrate;
mod keep_awake;
pub mod lanes;
pub mod metrics;
pub mod params;
pub mod particles;
pub mod perf;
pub mod reference;
#[cfg(feature = "render")]
pub mod render;
pub mod scene;
pub mod stage_clock;
pub mod step;
pub mod strands;
#[cfg(test)]
mod test_rng;
pub mod world;

pub use cloth::{ClothDesc, PinSpec};
pub use effects::{Effects, Wind};
pub use embed::{AdvanceReport, Snapshot, Soa, Vec3Out};
pub use error::{Result, WeftError};
pub use fabric::Fabric;
pub use metrics::Metrics;
pub use params::{Backend, Method, SolverParams};
pub use world::World;
