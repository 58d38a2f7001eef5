use super::*;
use proptest::prelude::*;

fn cols(p: &[[f32; 3]]) -> [Vec<f32>; 3] {
    [0, 1, 2].map(|k| p.iter().map(|v| v[k]).collect())
}

fn refs(c: &[Vec<f32>; 3]) -> [&[f32]; 3] {
    [&c[0], &c[1], &c[2]]
}

/// A flat `m x m` grid of spacing `s` at height `y`, its triangles offset by `first`.
fn sheet(m: u32, s: f32, y: f32, first: u32) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let mut p = Vec::new();
    for r in 0..m {
        for c in 0..m {
            p.push([c as f32 * s, y, r as f32 * s]);
        }
    }
    let mut t = Vec::new();
    for r in 0..m - 1 {
        for c in 0..m - 1 {
            let i = first + r * m + c;
            t.push([i, i + 1, i + m]);
            t.push([i + 1, i + m + 1, i + m]);
        }
    }
    (p, t)
}

/// Two 6 x 6 sheets (cloths 0 and 1) of spacing 1, the second at heights `y0` then `y1`,
/// shifted by half a cell so its particles project inside the first's triangles.
fn two_sheets(y0: f32, y1: f32) -> usize {
    let (mut rest, mut tris) = sheet(6, 1.0, 0.0, 0);
    let (upper, t2) = sheet(6, 1.0, 0.0, 36);
    rest.extend(upper.iter().map(|p| [p[0] + 0.3, 0.0, p[2] + 0.4]));
    tris.extend(t2);
    let group: Vec<u32> = (0..72).map(|i| (i >= 36) as u32).collect();
    let at = |y: f32| -> Vec<[f32; 3]> {
        rest.iter()
            .enumerate()
            .map(|(i, p)| if i >= 36 { [p[0], y, p[2]] } else { *p })
            .collect()
    };
    let (r, b, a) = (cols(&rest), cols(&at(y0)), cols(&at(y1)));
    let rule = RestRule::new(refs(&r), &group, 3.0).unwrap();
    count_crossings(refs(&b), refs(&a), &tris, &rule, 1.0).unwrap()
}

#[test]
fn a_sheet_through_another_crosses_and_one_that_stays_above_does_not() {
    // The upper sheet's interior particles project inside the lower sheet's triangles.
    assert!(two_sheets(0.3, -0.3) > 0, "passing through must count");
    assert!(two_sheets(-0.2, 0.4) > 0, "passing up through must count");
    assert_eq!(two_sheets(0.3, 0.1), 0, "approaching is not crossing");
    assert_eq!(two_sheets(0.3, 0.0), 0, "landing on the plane is not crossing");
    assert_eq!(two_sheets(0.3, 2.0), 0, "moving away is not crossing");
    // Both states out of reach: a far jump through is not seen (documented limit).
    assert_eq!(two_sheets(3.0, -3.0), 0);
}

#[test]
fn neighbours_and_particles_outside_the_prism_do_not_cross() {
    let rest = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.2, 0.0, 0.2]];
    let tri = [[0u32, 1, 2]];
    let r = cols(&rest);
    let run = |group: [u32; 4], from: [f32; 3], to: [f32; 3]| {
        let rule = RestRule::new(refs(&r), &group, 0.5).unwrap();
        let mut b = rest;
        b[3] = from;
        let mut a = rest;
        a[3] = to;
        let (b, a) = (cols(&b), cols(&a));
        count_crossings(refs(&b), refs(&a), &tri, &rule, 0.5).unwrap()
    };
    assert_eq!(run([0, 0, 0, 1], [0.2, 0.1, 0.2], [0.2, -0.1, 0.2]), 1);
    // Same cloth, within the skip distance of a vertex at rest: a neighbour.
    assert_eq!(run([0, 0, 0, 0], [0.2, 0.1, 0.2], [0.2, -0.1, 0.2]), 0);
    // Around the free edge: outside the prism after.
    assert_eq!(run([0, 0, 0, 1], [0.2, 0.1, 0.2], [1.2, -0.1, 1.2]), 0);
    // A vertex of the triangle is never tested against it.
    let rule = RestRule::new(refs(&r), &[0, 1, 2, 3], 0.5).unwrap();
    assert_eq!(count_crossings(refs(&r), refs(&r), &tri, &rule, 0.5).unwrap(), 0);
}

#[test]
fn bad_input_is_an_error() {
    let r = cols(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let rule = RestRule::new(refs(&r), &[0, 0, 1], 0.5).unwrap();
    assert!(count_crossings(refs(&r), refs(&r), &[[0, 1, 3]], &rule, 0.5).is_err());
    assert!(deepest_violation(refs(&r), &rule, 0.0).is_err());
    assert!(deepest_violation(refs(&r), &rule, f32::NAN).is_err());
    let bad = cols(&[[0.0; 3], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    assert!(deepest_violation(refs(&bad), &rule, 0.5).is_err());
    assert!(RestRule::new(refs(&bad), &[0, 0, 1], 0.5).is_err());
    assert!(RestRule::new(refs(&r), &[0, 0], 0.5).is_err());
    assert!(RestRule::new(refs(&r), &[0, 0, 1], -1.0).is_err());
}

#[test]
fn deepest_violation_of_two_cloths_and_of_a_neighbour() {
    let r = cols(&[[0.0; 3], [0.3, 0.0, 0.0], [5.0, 0.0, 0.0]]);
    // 0 and 1 in different cloths: 0.3 apart, distance 1 -> 0.7.
    let rule = RestRule::new(refs(&r), &[0, 1, 1], 0.5).unwrap();
    assert!((deepest_violation(refs(&r), &rule, 1.0).unwrap() - 0.7).abs() < 1e-6);
    // Same cloth, 0.3 apart at rest: neighbours under a skip of 0.5, not under 0.2.
    let rule = RestRule::new(refs(&r), &[0, 0, 0], 0.5).unwrap();
    assert_eq!(deepest_violation(refs(&r), &rule, 1.0).unwrap(), 0.0);
    let rule = RestRule::new(refs(&r), &[0, 0, 0], 0.2).unwrap();
    assert!(deepest_violation(refs(&r), &rule, 1.0).unwrap() > 0.69);
    assert!((share_closer(refs(&r), &rule, 1.0).unwrap() - 200.0 / 3.0).abs() < 1e-9);
}

proptest! {
    #[test]
    fn close_pairs_equal_a_brute_force(
        pts in prop::collection::vec((-2.0f32..2.0, -2.0f32..2.0, -2.0f32..2.0, 0u32..3), 0..60),
        reach in 0.05f32..1.5,
        skip in 0.0f32..1.0,
    ) {
        let n = pts.len();
        let x = [pts.iter().map(|p| p.0).collect::<Vec<_>>(), pts.iter().map(|p| p.1).collect(), pts.iter().map(|p| p.2).collect()];
        // Rest positions: a line, so some same-group pairs are neighbours.
        let rest = [(0..n).map(|i| i as f32 * 0.3).collect::<Vec<_>>(), vec![0.0; n], vec![0.0; n]];
        let group: Vec<u32> = pts.iter().map(|p| p.3).collect();
        let rule = RestRule::new(refs(&rest), &group, skip).unwrap();
        let mut got = Vec::new();
        close_pairs(refs(&x), &rule, reach, |i, j, _| got.push((i, j))).unwrap();
        got.sort_unstable();
        let mut want = Vec::new();
        for i in 0..n {
            for j in i + 1..n {
                if dist2(refs(&x), i, j) < reach * reach && rule.far(i, j) {
                    want.push((i, j));
                }
            }
        }
        prop_assert_eq!(got, want);
    }
}
