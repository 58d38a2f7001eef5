use super::*;

fn desc(rows: u32, cols: u32) -> ClothDesc {
    ClothDesc {
        rows,
        cols,
        ..ClothDesc::default()
    }
}

#[test]
fn grid_counts() {
    let b = desc(4, 5).build().unwrap();
    assert_eq!(b.positions.len(), 20);
    assert_eq!(b.triangles.len(), 2 * 3 * 4);
    let count = |k| b.edges.iter().filter(|e| e.kind == k).count();
    assert_eq!(count(ConstraintKind::Stretch), 4 * 4 + 3 * 5);
    assert_eq!(count(ConstraintKind::Shear), 2 * 3 * 4);
    assert_eq!(count(ConstraintKind::Bend), 4 * 3 + 2 * 5);
    assert_eq!(b.inv_mass.iter().filter(|&&w| w == 0.0).count(), 2);
    assert_eq!(b.tethers.len(), 18);
    for t in &b.tethers {
        assert!(b.inv_mass[t.anchor as usize] == 0.0 && b.inv_mass[t.particle as usize] > 0.0);
    }
}

#[test]
fn rest_lengths_match_positions() {
    let b = desc(6, 7).build().unwrap();
    for e in &b.edges {
        let (p, q) = (b.positions[e.a as usize], b.positions[e.b as usize]);
        let l = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
        assert!((l - e.rest).abs() < 1e-5, "{e:?} {l}");
    }
}

#[test]
fn skewed_directions_start_at_rest() {
    // u and v 86.8 degrees apart: every rest length, the shear diagonals included, is the
    // built distance (they used to be s * sqrt 2, 3% off, and the cloth moved by itself).
    let b = ClothDesc {
        u: [1.0, 0.0, 0.2],
        v: [0.0, -1.0, 0.3],
        ..desc(6, 7)
    }
    .build()
    .unwrap();
    for e in &b.edges {
        let (p, q) = (b.positions[e.a as usize], b.positions[e.b as usize]);
        let l = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
        assert!((l - e.rest).abs() < 1e-6 * e.rest.max(1.0), "{e:?} {l}");
    }
}

#[test]
fn bad_descriptions_are_errors() {
    assert!(desc(0, 5).build().unwrap_err().to_string().contains("rows x cols"));
    // A mass whose inverse is infinite is refused; a subnormal one with a finite inverse is not.
    let mut d = desc(3, 3);
    d.fabric.mass = 1e-40;
    assert!(d.build().unwrap_err().to_string().contains("fabric.mass"));
    d.fabric.mass = 1e-38;
    assert!(d.build().is_ok(), "a mass whose inverse (1e38) is finite is a mass");
    let d = ClothDesc {
        spacing: 0.0,
        ..desc(3, 3)
    };
    assert!(d.build().unwrap_err().to_string().contains("spacing"));
    let d = ClothDesc {
        spacing: f32::NAN,
        ..desc(3, 3)
    };
    assert!(d.build().is_err());
    let d = ClothDesc {
        u: [0.0, 0.0, 0.0],
        ..desc(3, 3)
    };
    assert!(d.build().unwrap_err().to_string().contains("`u`"));
    let d = ClothDesc {
        u: [0.0, 1.0, 0.0],
        v: [0.0, 2.0, 0.0],
        ..desc(3, 3)
    };
    assert!(d.build().is_err());
    let d = ClothDesc {
        pins: vec![PinSpec::Row(3)],
        ..desc(3, 3)
    };
    assert!(d.build().unwrap_err().to_string().contains("row 3"));
    let d = ClothDesc {
        pins: vec![PinSpec::Indices(vec![9])],
        ..desc(3, 3)
    };
    assert!(d.build().is_err());
}

#[test]
fn region_pins() {
    let d = ClothDesc {
        pins: vec![PinSpec::Region {
            min: [-1.0, 0.99, -1.0],
            max: [10.0, 1.01, 1.0],
        }],
        ..desc(3, 4)
    };
    let b = d.build().unwrap();
    assert_eq!(b.inv_mass.iter().filter(|&&w| w == 0.0).count(), 4);
}
