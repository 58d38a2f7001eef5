//! Helpers shared by the integration tests.
#![allow(dead_code)]

use weft::{ClothDesc, Effects, Fabric, PinSpec, SolverParams, World};

/// A world with one cloth.
pub fn world_with(desc: &ClothDesc, params: SolverParams, effects: Effects) -> World {
    let mut w = World::new(params, effects).expect("valid world");
    w.add_cloth(desc).expect("valid cloth");
    w
}

/// A hanging cloth pinned at two corners.
pub fn hanging(rows: u32, cols: u32) -> ClothDesc {
    ClothDesc {
        rows,
        cols,
        spacing: 0.05,
        pins: vec![PinSpec::FirstRowCorners],
        fabric: Fabric::preset("cotton").unwrap(),
        ..Default::default()
    }
}

/// Bit patterns of every position and velocity.
pub fn state_bits(w: &World) -> Vec<u32> {
    let p = w.positions();
    let v = w.velocities();
    p.iter().chain(v.iter()).flat_map(|a| a.iter().map(|f| f.to_bits())).collect()
}
