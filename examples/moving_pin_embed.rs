//! A hand dragging a cloth by one corner: each fixed step the host moves a pinned particle
//! along a path (`set_pin_position` inside `advance_with`), and the cloth follows smoothly.
//! Halfway through, the host stiffens the fabric at run time and later rolls back to a
//! snapshot.
//!
//! Run: `cargo run --example moving_pin_embed`

use weft::{ClothDesc, Effects, Fabric, PinSpec, SolverParams, World};

fn main() -> weft::Result<()> {
    let mut world = World::new(SolverParams::default(), Effects::gravity())?;
    let cloth = world.add_cloth(&ClothDesc {
        rows: 20,
        cols: 20,
        spacing: 0.05,
        fabric: Fabric::preset("wool")?,
        pins: vec![PinSpec::Cells(vec![[0, 0]])],
        tethers: None,
        ..Default::default()
    })?;
    let corner = 0; // particle index of cell (0, 0)
    let start = world.position(corner)?;
    let mut positions = vec![0.0f32; 3 * world.particle_count()];
    let mut snapshot = None;

    for frame in 0..240 {
        let report = world.advance_with(1.0 / 60.0, |w| {
            // The hand: a slow figure of eight in the x-y plane, as a function of simulated time.
            let t = w.time() as f32;
            let hand = mint::Point3 {
                x: start.x + 0.4 * (0.8 * t).sin(),
                y: start.y + 0.15 * (1.6 * t).sin(),
                z: start.z,
            };
            w.set_pin_position(corner, hand)
        })?;
        if frame == 120 {
            // Stiffen the fabric without a jerk; keep a snapshot to roll back to.
            world.set_cloth_compliance(cloth, 0.0, 1e-6, 1e-4)?;
            snapshot = Some(world.snapshot());
        }
        world.read_positions(&mut positions[..])?;
        if frame % 40 == 0 {
            let m = world.metrics();
            println!(
                "frame {frame:3}: steps {}, hand at ({:+.3}, {:+.3}), far corner y = {:+.3}, max strain {:.4}",
                report.steps,
                positions[0],
                positions[1],
                positions[positions.len() - 2],
                m.max_strain
            );
        }
    }
    if let Some(s) = snapshot {
        world.restore_snapshot(&s)?;
        println!("rolled back to step {}", world.steps());
    }
    Ok(())
}
