//! The smallest engine loop: build a cloth in code, advance by frame time, read positions and
//! normals into buffers the renderer owns.
//!
//! Run: `cargo run --example minimal_embed`

use weft::{ClothDesc, Effects, Fabric, PinSpec, SolverParams, World};

fn main() -> weft::Result<()> {
    let mut world = World::new(SolverParams::default(), Effects::gravity())?;
    world.add_cloth(&ClothDesc {
        rows: 24,
        cols: 24,
        spacing: 0.04,
        fabric: Fabric::preset("cotton")?,
        pins: vec![PinSpec::FirstRowCorners],
        ..Default::default()
    })?;

    // The renderer's vertex buffers: allocated once, filled every frame.
    let n = world.particle_count();
    let mut positions = vec![[0.0f32; 3]; n];
    let mut normals = vec![[0.0f32; 3]; n];

    // Frame times as a real engine sees them: uneven.
    let frames = [0.016, 0.017, 0.033, 0.015, 0.016, 0.050, 0.016];
    for (k, &frame_dt) in frames.iter().cycle().take(120).enumerate() {
        let report = world.advance(frame_dt)?;
        world.interpolated_positions(report.alpha, &mut positions[..])?;
        world.read_normals(&mut normals[..])?;
        if k % 30 == 0 {
            let low = positions.iter().map(|p| p[1]).fold(f32::INFINITY, f32::min);
            println!(
                "frame {k:3}: {} steps (capped: {}), t = {:.3} s, lowest point y = {low:.3} m, normal[0] = {:?}",
                report.steps,
                report.capped,
                world.time(),
                normals[0]
            );
        }
    }
    Ok(())
}
