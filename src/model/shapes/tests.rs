use super::*;

fn resolve(c: &ShapeContact, p: [f32; 3]) -> [f32; 3] {
    let d = c.depth.max(0.0);
    [0, 1, 2].map(|k| p[k] + c.normal[k] * d)
}

#[test]
fn plane_proximity_and_below() {
    let s = Shape::plane([0.0, 1.0, 0.0], [0.0, 2.0, 0.0]).unwrap();
    assert!(s.contact([0.0, 2.0, 0.0], [0.0, 1.5, 0.0], 0.01, 0.02).is_none());
    let c = s.contact([0.0, 2.0, 0.0], [0.3, -5.0, 0.0], 0.01, 0.02).unwrap();
    assert_eq!(c.normal, [0.0, 1.0, 0.0]);
    let q = resolve(&c, [0.3, -5.0, 0.0]);
    assert!((q[1] - 1.01).abs() < 1e-6, "{q:?}");
}

#[test]
fn sphere_fast_particle_does_not_tunnel() {
    let s = Shape::Sphere {
        center: [0.0; 3],
        radius: 0.5,
    };
    // passes straight through in one step, ends clear on the far side
    let (x, p) = ([0.1, 3.0, 0.0], [0.1, -3.0, 0.0]);
    let c = s.contact(x, p, 0.01, 0.02).expect("crossing found");
    assert!(c.normal[1] > 0.9, "{c:?}");
    let q = resolve(&c, p);
    assert!(q[1] > 0.0 && s.signed_distance(q) > 0.0, "{q:?}");
    // a miss stays a miss
    assert!(s.contact([1.0, 3.0, 0.0], [1.0, -3.0, 0.0], 0.01, 0.02).is_none());
    // resting inside the reach
    let c = s.contact([0.0, 0.515, 0.0], [0.0, 0.505, 0.0], 0.01, 0.02).unwrap();
    assert!((resolve(&c, [0.0, 0.505, 0.0])[1] - 0.51).abs() < 1e-6);
}

#[test]
fn capsule_and_box_catch_fast_particles() {
    let cap = Shape::Capsule {
        a: [-1.0, 0.0, 0.0],
        b: [1.0, 0.0, 0.0],
        radius: 0.2,
    };
    let (x, p) = ([0.3, 2.0, 0.1], [0.3, -2.0, 0.1]);
    let c = cap.contact(x, p, 0.01, 0.02).unwrap();
    assert!(c.normal[1] > 0.5 && cap.signed_distance(resolve(&c, p)) > 0.0, "{c:?}");
    let bx = Shape::Box {
        center: [0.0; 3],
        half: [0.5, 0.1, 0.5],
        axes: Shape::axes_from_euler_deg([0.0, 30.0, 0.0]),
    };
    let c = bx.contact([0.0, 2.0, 0.0], [0.0, -2.0, 0.0], 0.01, 0.02).unwrap();
    assert!((c.normal[1] - 1.0).abs() < 1e-6, "{c:?}");
    assert!((resolve(&c, [0.0, -2.0, 0.0])[1] - 0.11).abs() < 1e-5);
    // inside, started inside: least penetration (here +x face)
    let c = bx.contact([0.0, 0.0, 0.0], [0.0, 0.0, 0.0], 0.01, 0.02).unwrap();
    assert!(c.normal[1].abs() > 0.99, "{c:?}");
    // entered from the side: pushed back out of that side
    let (x, p) = ([2.0, 0.0, 0.0], [0.3, 0.05, 0.0]);
    let axes = Shape::axes_from_euler_deg([0.0; 3]);
    let ab = Shape::Box {
        center: [0.0; 3],
        half: [0.5, 0.1, 0.5],
        axes,
    };
    let c = ab.contact(x, p, 0.01, 0.02).unwrap();
    assert_eq!(c.normal, [1.0, 0.0, 0.0]);
}

#[test]
fn validation_and_moves() {
    assert!(Shape::plane([0.0; 3], [0.0; 3]).is_err());
    assert!(Shape::Sphere {
        center: [0.0; 3],
        radius: -1.0
    }
    .validate()
    .is_err());
    assert!(Shape::Box {
        center: [0.0; 3],
        half: [1.0; 3],
        axes: [[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    }
    .validate()
    .is_err());
    let s = Shape::Sphere {
        center: [0.0; 3],
        radius: 1.0,
    }
    .translated([1.0, 2.0, 3.0]);
    assert_eq!(s.signed_distance([1.0, 2.0, 3.0]), -1.0);
    let n = any_orthogonal([0.0, 0.0, 1.0]);
    assert!(dot(n, [0.0, 0.0, 1.0]).abs() < 1e-6);
}
