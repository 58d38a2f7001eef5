#![doc = include_str!("../README.md")]
#![warn(missing_docs)]
pub mod accuracy;
#[cfg(feature = "capi")]
pub mod capi;
pub mod constraints;
pub mod data;
pub mod embed;
pub mod error;
pub mod export;
pub mod files;
#[doc(hidden)]
pub mod fuzzing;
pub mod integrate;
pub mod model;
pub mod obstacles;
pub mod perf;
pub mod reference;
#[cfg(feature = "render")]
pub mod render;
pub mod scene;
pub mod self_collision;
pub mod strands;
pub mod suite;
#[cfg(test)]
mod test_rng;
pub mod world;

pub use embed::{AdvanceReport, Snapshot, Soa, Vec3Out};
pub use error::{Result, WeftError};
pub use model::cloth::{ClothDesc, PinSpec};
pub use model::effects::{Effects, Wind};
pub use model::fabric::Fabric;
pub use model::params::{Backend, Method, SolverParams};
pub use world::metrics::Metrics;
pub use world::threads::ThreadChoiceReport;
pub use world::World;
