//! `weft check SCENE`.

use std::path::Path;
use std::process::ExitCode;

use weft::model::budget::human_bytes;
use weft::scene::Scene;

pub fn check(path: &Path) -> weft::Result<ExitCode> {
    let (scene, _) = Scene::load(path)?;
    let world = scene.world()?;
    println!("scene {}: valid", path.display());
    print!("{}", describe(&scene, &world));
    Ok(ExitCode::SUCCESS)
}

/// A human-readable account of what a scene simulates.
pub fn describe(scene: &Scene, world: &weft::World) -> String {
    let p = world.params();
    let mut s = String::new();
    let n = world.particle_count();
    let pad = world.particles().padded_len();
    s += &format!("  cloths        {}\n", world.cloths().len());
    for (k, c) in world.cloths().iter().enumerate() {
        s += &format!("    cloth {k}: {} x {} particles, thickness {} m\n", c.rows, c.cols, c.thickness);
    }
    s += &format!("  strands       {}\n", world.strands().iter().map(|g| g.count as u64).sum::<u64>());
    for (k, g) in world.strands().iter().enumerate() {
        let sc = &g.scalp;
        let shape = if sc.is_sphere() {
            format!("sphere r {} m", sc.radii[0])
        } else {
            format!("ellipsoid radii {:?} m", sc.radii)
        };
        s += &format!(
            "    strands {k}: {} x {} points on a {shape} at {:?}, polar {:?} deg, thickness {} m\n",
            g.count, g.points, sc.center, sc.polar_degrees, g.thickness
        );
    }
    s += &format!("  particles     {n} (padded to {pad})\n");
    s += &format!(
        "  constraints   {} distance in {} colours, {} tethers\n",
        world.constraint_count(),
        world.colour_count(),
        world.tether_count()
    );
    s += &format!("  triangles     {}\n", world.triangles().len());
    if world.obstacles().is_empty() {
        s += "  obstacles     none\n";
    } else {
        s += &format!(
            "  obstacles     {} (default friction {})\n",
            world.obstacles().len(),
            world.friction()
        );
        for (k, o) in world.obstacles().iter().enumerate() {
            s += &format!("    obstacle {k}: {}\n", o.describe());
        }
    }
    let all = ["gravity", "wind", "drag", "self_collision"];
    let mut on = world.effects().named();
    if world.self_collision().is_some() {
        on.push("self_collision");
    }
    let off: Vec<_> = all.iter().filter(|e| !on.contains(e)).collect();
    s += &format!(
        "  effects on    {}\n",
        if on.is_empty() { "none".to_string() } else { on.join(", ") }
    );
    s += &format!(
        "  effects off   {}\n",
        if off.is_empty() {
            "none".to_string()
        } else {
            off.iter().map(|e| e.to_string()).collect::<Vec<_>>().join(", ")
        }
    );
    if let Some(c) = world.self_collision() {
        s += &format!(
            "  self-collision distance {} m, {} response, {} broadphase, friction {}, travel {} (reach {} m)\n",
            world.self_collision_distance(),
            c.response.name(),
            c.broadphase.name(),
            c.friction,
            c.travel,
            c.query_factor() * world.self_collision_distance()
        );
    }
    s += &format!(
        "  solver        dt {} s, {} substeps x {} iterations, {:?} backend, threads {}\n",
        p.dt,
        p.substeps,
        p.iterations,
        p.backend,
        if p.threads == 0 { "all".to_string() } else { p.threads.to_string() }
    );
    s += &format!(
        "  run           {} steps ({:.2} s simulated), {} frames\n",
        scene.output.steps.0,
        scene.output.steps.0 as f64 * p.dt as f64,
        scene.output.frames.0
    );
    let limit = match weft::model::budget::MemoryLimit::current() {
        Ok(Some(l)) => format!(", limit {} ({})", human_bytes(l.bytes), l.source),
        Ok(None) => String::new(),
        Err(e) => format!(", limit unreadable: {e}"),
    };
    s += &format!(
        "  memory        ~{} (estimated from the counts{limit})\n",
        human_bytes(scene.memory_counts().bytes().max(world.memory_counts().bytes()))
    );
    s
}
