//! The f64 reference with obstacles and self-collision against the f32 world.

use super::ReferenceWorld;
use crate::scene::Scene;
use crate::World;

/// A small cotton sheet dropped from 0.7 m onto `extra` (scene text: obstacles), tethers off.
fn sheet(rows: u32, extra: &str, substeps: u32, iterations: u32) -> World {
    sheet_at(0.7, rows, extra, substeps, iterations)
}

/// [`sheet`] from height `y`.
fn sheet_at(y: f64, rows: u32, extra: &str, substeps: u32, iterations: u32) -> World {
    let text = format!(
        r#"
[solver]
dt = 0.016666667
substeps = {substeps}
iterations = {iterations}
[effects]
gravity = [0.0, -9.81, 0.0]
friction = 0.5
[[cloth]]
rows = {rows}
cols = 12
spacing = 0.02
origin = [-0.11, {y}, -0.11]
u = [1.0, 0.0, 0.0]
v = [0.0, 0.0, 1.0]
fabric = "cotton"
tethers = false
{extra}
"#
    );
    Scene::parse(&text, "test").unwrap().world().unwrap()
}

const SPHERE: &str = r#"
[[obstacle]]
kind = "sphere"
center = [0.0, 0.5, 0.0]
radius = 0.1
[[obstacle]]
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
"#;

/// Capsule, rotated box and a moving sphere under one sheet.
const SHAPES: &str = r#"
[[obstacle]]
kind = "capsule"
a = [-0.2, 0.55, -0.05]
b = [0.2, 0.55, 0.05]
radius = 0.03
[[obstacle]]
kind = "box"
center = [0.06, 0.45, 0.06]
half_extents = [0.05, 0.1, 0.05]
rotation = [0.0, 30.0, 10.0]
[[obstacle]]
kind = "sphere"
center = [-0.06, 0.4, -0.06]
radius = 0.06
velocity = [0.0, 0.5, 0.0]
friction = 0.2
"#;

/// Largest distance between the f32 world's and the f64 reference's particles after `steps`
/// steps at the world's settings, and the reference itself.
fn compare(mut w: World, steps: usize) -> (f64, ReferenceWorld) {
    let mut r = ReferenceWorld::new(&w.describe());
    assert_eq!(r.missing_feature(), None);
    let dt = w.params().dt;
    for _ in 0..steps {
        w.step(dt).unwrap();
        r.step(dt as f64);
    }
    let p = w.particles();
    let gap = (0..w.particle_count())
        .map(|i| {
            let a = p.position(i);
            (0..3).map(|k| (a[k] as f64 - r.x[i][k]).powi(2)).sum::<f64>().sqrt()
        })
        .fold(0.0, f64::max);
    (gap, r)
}

/// Smallest signed distance of the reference's particles to its obstacles, minus the
/// cloth thickness (negative: closer than the thickness).
fn clearance(r: &ReferenceWorld) -> f64 {
    r.x.iter()
        .enumerate()
        .flat_map(|(i, x)| r.obstacles.iter().map(move |o| o.signed_distance(*x, r.time) - r.th[i]))
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn f64_reference_keeps_the_sheet_outside_the_sphere_and_agrees_with_the_world() {
    // 40 steps: the sheet falls 0.1 m onto the ball and wraps it.
    let (gap, r) = compare(sheet(12, SPHERE, 16, 4), 40);
    let th = r.th[0];
    let c = clearance(&r);
    assert!(c > -1e-3 * th, "a particle sits {:.3e} m inside the thickness layer", -c);
    assert_eq!(r.obstacle_penetration(1e-9).1, 0);
    let touching =
        r.x.iter()
            .filter(|x| r.obstacles[0].signed_distance(**x, r.time) < 2.0 * th)
            .count();
    assert!(touching > 20, "the sheet lies on the ball: {touching} particles touch it");
    // f32 and f64 runs of the same method: their rounding differences (1e-6 m before the
    // impact) are amplified by the stiff cotton's impact and by contacts switching on and off,
    // to 3e-3 m after 40 steps; a 1e-7 m perturbation of the f64 run grows as fast.
    assert!(gap < 5e-3, "f32 world and f64 reference differ by {gap:.3e} m");
    eprintln!("sphere: f32 vs f64 max gap {gap:.3e} m, clearance {c:.3e} m");
}

#[test]
fn f64_reference_agrees_with_the_world_on_capsule_box_and_moving_sphere() {
    // A short run: the sheet lands on the capsule, the box and the rising ball (from step 4).
    // Sliding over the box's edges (where the contact face switches) amplifies rounding the
    // most: 1e-3 m at step 7, centimetres by step 40.
    let (gap, r) = compare(sheet_at(0.59, 12, SHAPES, 16, 16), 8);
    let c = clearance(&r);
    eprintln!("shapes: f32 vs f64 max gap {gap:.3e} m, clearance {c:.3e} m");
    assert!(c > -1e-3 * r.th[0], "a particle sits {:.3e} m inside the thickness layer", -c);
    assert!(gap < 2e-3, "f32 world and f64 reference differ by {gap:.3e} m");
}

/// Two cotton sheets with self-collision: a 10 x 10 one held by two opposite edges and an
/// 8 x 8 one dropped onto it from 3 cm, with the travel bound `travel`.
fn stack(response: &str, substeps: u32, travel: f32) -> World {
    let sheet = |rows: u32, y: f64, x0: f64, pins: &str| {
        format!(
            "[[cloth]]\nrows = {rows}\ncols = {rows}\nspacing = 0.02\norigin = [{x0}, {y}, {x0}]\nu = [1.0, 0.0, 0.0]\nv = [0.0, 0.0, 1.0]\nfabric = \"cotton\"\nthickness = 0.02\ntethers = false\npins = [{pins}]\n"
        )
    };
    let text = format!(
        "[solver]\ndt = 0.016666667\nsubsteps = {substeps}\niterations = 1\n[effects]\ngravity = [0.0, -9.81, 0.0]\ndrag = 0.0005\n[effects.self_collision]\nresponse = \"{response}\"\nfriction = 0.3\ntravel = {travel}\n{}{}",
        sheet(10, 1.0, -0.09, "{ row = 0 }, { row = 9 }"),
        sheet(8, 1.03, -0.07, "")
    );
    Scene::parse(&text, "test").unwrap().world().unwrap()
}

/// Mean height of the particles `range`.
fn mean_y(x: &[[f64; 3]], range: std::ops::Range<usize>) -> f64 {
    let n = range.len() as f64;
    x[range].iter().map(|p| p[1]).sum::<f64>() / n
}

#[test]
fn f64_self_collision_agrees_with_the_world_on_two_stacked_sheets() {
    // At travel 0.25 the clamp (0.3 m/s relative to the mean) slows the falling sheet.
    let mut last = Vec::new();
    for (response, travel) in [("pbd", 1.0), ("vccpbd", 1.0), ("vccpbd", 0.25)] {
        let steps = 30;
        let mut w = stack(response, 16, travel);
        let (gap, r) = compare(stack(response, 16, travel), steps);
        for _ in 0..steps {
            w.step(w.params().dt).unwrap();
        }
        let world_pct = w.measure_self_collision().unwrap();
        let pct = r.self_penetration_pct().unwrap();
        let (lower, upper) = (mean_y(&r.x, 0..100), mean_y(&r.x, 100..164));
        eprintln!(
            "stack {response}, travel {travel}: f32 vs f64 max gap {gap:.3e} m, self-penetration {pct:.2}% (world {world_pct:.2}%), upper sheet {:.4} m above the lower",
            upper - lower
        );
        assert!(pct < 1.0, "{response}: {pct}% of the particles in self-penetration");
        assert!(upper - lower > 0.01, "{response}: the upper sheet must rest on the lower one");
        // The over-relaxed contact average (`RELAXATION`) turns a contact that f32 and f64
        // decide differently at the threshold into a larger move: the two drift apart by up to
        // about 5e-4 m over the 30 steps; the bound is 5% of the 2 cm spacing.
        assert!(gap < 1e-3, "{response}: f32 world and f64 reference differ by {gap:.3e} m");
        last.push(w.positions()[1].to_vec());
    }
    let moved = last[1].iter().zip(&last[2]).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
    assert!(moved > 1e-4, "the travel bound changes the motion: {moved:.3e} m");
}

#[test]
fn without_self_collision_the_reference_sheets_pass_through_each_other() {
    let mut bare = stack("pbd", 16, 1.0);
    bare.set_self_collision(None).unwrap();
    let mut r = ReferenceWorld::new(&bare.describe());
    (0..30).for_each(|_| r.step(1.0 / 60.0));
    let (lower, upper) = (mean_y(&r.x, 0..100), mean_y(&r.x, 100..164));
    assert!(upper < lower, "the upper sheet falls through: {upper} vs {lower}");
}

#[test]
fn mesh_obstacles_are_named_as_missing() {
    let w = sheet(
        4,
        "[[obstacle]]\nkind = \"mesh\"\ndress_form = 400\nscale = 0.3\nbroadphase = \"bvh\"\n",
        4,
        1,
    );
    assert_eq!(
        ReferenceWorld::new(&w.describe()).missing_feature(),
        Some("triangle-mesh obstacles")
    );
    assert_eq!(ReferenceWorld::new(&sheet(4, SPHERE, 4, 1).describe()).missing_feature(), None);
}
