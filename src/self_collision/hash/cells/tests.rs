//! Tests of the half-shell cell query: equal to the particle query and to the brute force.

use super::*;
use crate::data::exec::Exec;
use crate::self_collision::neighbours::{pair_reach2, within};
use crate::test_rng::signed;

use super::super::rest::tests::{lattices, Scene};

/// Brute force over all pairs with the rule of `hash::rest` (upper lists).
fn brute(p: &[Vec<f32>; 3], rest: &[Vec<f32>; 3], cloth: &[u32], reach: f32, skip: f32) -> Neighbours {
    let n = cloth.len();
    let mut nb = Neighbours::new();
    nb.fill_serial(n, |i, buf| {
        for j in i + 1..n {
            let d = |k: usize| rest[k][i] - rest[k][j];
            let skipped = cloth[i] == cloth[j] && d(0) * d(0) + d(1) * d(1) + d(2) * d(2) <= skip * skip;
            if within(p[0][i], p[1][i], p[2][i], p[0][j], p[1][j], p[2][j], reach * reach) && !skipped {
                buf.push(j as u32);
            }
        }
    })
    .unwrap();
    nb
}

/// Every query of the scene (cells parallel on 1 and 2 threads, cells serial, cells with each
/// `Exec`, the particle query) equals the brute force; returns the number of kept pairs.
fn check(s: &Scene, spacing: f32, reach: f32, skip: f32) -> usize {
    let (p, rest, cloth) = s;
    let n = cloth.len();
    let want = brute(p, rest, cloth, reach, skip);
    let mut h = SpatialHash::new(n);
    h.build(&p[0], &p[1], &p[2], n, spacing).unwrap();
    h.attach_rest([&rest[0], &rest[1], &rest[2]], cloth).unwrap();
    let mut got = Neighbours::new();
    for t in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(t).build().unwrap();
        pool.install(|| h.query_upper_unskipped_cells(reach, skip, &mut got)).unwrap();
        assert_eq!(got, want, "cells, {t} threads, spacing {spacing}, reach {reach}");
    }
    h.query_upper_unskipped_cells_serial(reach, skip, &mut got).unwrap();
    assert_eq!(got, want, "cells serial");
    for exec in [Exec::Scalar, Exec::Simd, Exec::Parallel, Exec::ScalarParallel] {
        h.query_upper_unskipped_cells_exec(reach, skip, &mut got, exec).unwrap();
        assert_eq!(got, want, "cells, {exec:?}");
    }
    want.total()
}

#[test]
fn cells_query_equals_the_brute_force_on_lattices() {
    let h = 0.01f32;
    // Crumpled, partly overlapping, one particle NaN.
    let mut s = lattices(14, h, 1.0, 0.5, 17);
    s.0[1][40] = f32::NAN;
    assert!(check(&s, 3.0 * h, 3.0 * h, 3.003 * h) > 200);
    assert!(check(&s, 4.5 * h, 3.0 * h, 3.003 * h) > 200, "cells wider than the reach");
    // Flat lattices one spacing apart, exactly on the cell faces: all boundary particles.
    let flat = lattices(12, h, 0.0, 1.0, 1);
    assert!(check(&flat, 3.0 * h, 3.0 * h, 3.003 * h) > 100);
    assert!(check(&flat, 2.0 * h, 2.0 * h, 1.001 * h) > 100, "skip below the reach");
    // A zero skip keeps every pair within reach (coincident rest positions excepted).
    assert!(check(&s, 3.0 * h, 3.0 * h, 0.0) > 1000);
}

#[test]
fn cells_query_handles_a_sparse_cloud_far_coordinates_and_the_all_pairs_path() {
    // A cloud far wider than the cells: about as many occupied cells as particles, so many
    // buckets hold several cells.
    let mut rng = signed(23);
    let n = 1500;
    let p: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| 0.5 * rng()).collect());
    let rest: [Vec<f32>; 3] = std::array::from_fn(|k| (0..n).map(|i| ((i * (k + 3)) % 97) as f32 * 0.01).collect());
    let cloth: Vec<u32> = (0..n as u32).map(|i| i % 3).collect();
    let mut s = (p, rest, cloth);
    assert!(check(&s, 0.05, 0.05, 0.2) > 300);
    // Saturated cell coordinates and a particle at infinity.
    for (i, v) in [(3usize, 1e30f32), (4, 1e30), (5, -1e30), (6, f32::INFINITY)] {
        for k in 0..3 {
            s.0[k][i] = v;
        }
    }
    assert!(check(&s, 0.05, 0.05, 0.2) > 300);
    // A spacing below the radius's rounding margin: every particle scans all slots.
    let z = [vec![0.0f32; 6], vec![0.0; 6], vec![0.0; 6]];
    let rest = [vec![0.0f32, 1.0, 2.0, 3.0, 4.0, 5.0], vec![0.0; 6], vec![0.0; 6]];
    assert_eq!(check(&(z, rest, vec![0, 0, 0, 1, 1, 1]), 1e-30, 1e-30, 1.0), 11);
}

#[test]
fn cells_query_needs_the_rest_data_and_checks_its_arguments() {
    let s = lattices(4, 0.01, 0.3, 1.0, 3);
    let n = s.2.len();
    let mut h = SpatialHash::new(n);
    h.build(&s.0[0], &s.0[1], &s.0[2], n, 0.03).unwrap();
    let mut got = Neighbours::new();
    assert!(h.query_upper_unskipped_cells(0.03, 0.01, &mut got).is_err(), "no rest data");
    h.attach_rest([&s.1[0], &s.1[1], &s.1[2]], &s.2).unwrap();
    assert!(h.query_upper_unskipped_cells(0.03, 0.01, &mut got).is_ok());
    assert!(h.query_upper_unskipped_cells(0.06, 0.01, &mut got).is_err(), "beyond the spacing");
    assert!(h.query_upper_unskipped_cells_serial(0.03, f32::NAN, &mut got).is_err());
}

/// Asserts that the lanes' member test answers every slot of `hs` as the scalar test does, for
/// the search radius `r`, and sets no bit past a bucket; returns the slots checked and whether a
/// bucket held more than a lane group.
fn assert_member_lanes(hs: &SpatialHash, r: f32) -> (usize, bool) {
    let (mut checked, mut big) = (0, false);
    for b in 0..hs.table_size {
        let (s, e) = (hs.cell_start[b] as usize, hs.cell_start[b + 1] as usize);
        if s == e {
            continue;
        }
        big |= e - s > LANES;
        let home = hs.cell_of_slot(s);
        for k in (s..e).step_by(LANES) {
            let bits = hs.member_lanes(k, e, home, r);
            for slot in k..e.min(k + LANES) {
                assert_eq!(bits & (1 << (slot - k)) != 0, hs.member(slot, home, r), "slot {slot}");
                checked += 1;
            }
            assert_eq!(bits >> (e.min(k + LANES) - k), 0, "no bits past the bucket");
        }
    }
    (checked, big)
}

/// The lanes' member test gives every slot the scalar test's answer: a crumpled lattice
/// (buckets of more than eight particles), particles exactly on cell faces, and saturated or
/// far coordinates (the lanes' scalar fallback).
#[test]
fn member_lanes_equal_the_scalar_member_test() {
    let h = 0.01f32;
    let mut scenes = vec![lattices(14, h, 1.0, 0.5, 17), lattices(12, h, 0.0, 1.0, 1)];
    let mut far = lattices(6, h, 1.0, 0.5, 5);
    for (i, v) in [(3usize, 1e30f32), (4, -1e30), (9, 3e5), (10, 4.2e4)] {
        far.0[i % 3][i] = v;
    }
    scenes.push(far);
    let mut checked = 0;
    for (p, rest, cloth) in &scenes {
        let n = cloth.len();
        let mut hs = SpatialHash::new(n);
        hs.build(&p[0], &p[1], &p[2], n, 3.0 * h).unwrap();
        hs.attach_rest([&rest[0], &rest[1], &rest[2]], cloth).unwrap();
        let (slots, big) = assert_member_lanes(&hs, search_radius(3.0 * h));
        checked += slots;
        assert!(big || n < 300, "a bucket of more than eight particles");
    }
    assert!(checked > 600, "{checked}");
}

/// With the particles' travels attached, every form of the query (lanes and scalar, serial and
/// parallel) keeps each pair within its own reach `d + (t_i + t_j) d`, as the brute force
/// does: cells wide enough for all (every particle a member), and cells sized for the slower
/// particles only, the faster searching boxes of their own (up to seven cells an axis); a
/// `max_dist` short of the members' reach is refused, and a new build forgets the travels.
#[test]
fn cells_query_keeps_each_pair_within_its_own_reach() {
    let h = 0.01f32;
    let (p, rest, cloth) = lattices(14, h, 1.0, 0.5, 23);
    let n = cloth.len();
    let t: Vec<f32> = (0..n)
        .map(|i| 0.25 + 0.125 * ((i * 5) % 7) as f32 + 0.01 * (i % 3) as f32)
        .collect();
    let (d, skip) = (h, 3.003 * h);
    let top = t.iter().copied().fold(0.0f32, f32::max);
    let reach = d + (top + top) * d;
    let all = brute(&p, &rest, &cloth, reach, skip);
    let mut want = all.clone();
    want.retain(|i, j| {
        let j = j as usize;
        within(p[0][i], p[1][i], p[2][i], p[0][j], p[1][j], p[2][j], pair_reach2(d, t[i], t[j]))
    });
    assert!(
        want.total() > 100 && want.total() < all.total(),
        "{} of {}",
        want.total(),
        all.total()
    );
    let mut hsh = SpatialHash::new(n);
    let mut got = Neighbours::new();
    for cell in [top, 0.6, 0.25, 0.0] {
        let members = d + (cell + cell) * d;
        hsh.build(&p[0], &p[1], &p[2], n, members).unwrap();
        hsh.attach_rest([&rest[0], &rest[1], &rest[2]], &cloth).unwrap();
        assert!(hsh.attach_travel(d, &t[..n - 1], cell).is_err());
        assert!(hsh.attach_travel(d, &t, -1.0).is_err());
        hsh.attach_travel(d, &t, cell).unwrap();
        for exec in [Exec::Scalar, Exec::Simd, Exec::Parallel, Exec::ScalarParallel] {
            hsh.query_upper_unskipped_cells_exec(members, skip, &mut got, exec).unwrap();
            assert_eq!(got, want, "{exec:?}, cell travel {cell}");
        }
        let short = members * 0.99;
        assert!(
            hsh.query_upper_unskipped_cells(short, skip, &mut got).is_err(),
            "cell travel {cell}"
        );
    }
    hsh.build(&p[0], &p[1], &p[2], n, reach).unwrap();
    hsh.attach_rest([&rest[0], &rest[1], &rest[2]], &cloth).unwrap();
    hsh.query_upper_unskipped_cells_exec(reach, skip, &mut got, Exec::Simd).unwrap();
    assert_eq!(got, all, "travels forgotten by the build");
}

/// The parallel walk's tasks cut the slots: a crowd of particles in one cell (a bucket longer
/// than a task, so tasks inside it walk no bucket) beside a sparse cloud. The tasks' buckets
/// tile the table, each bucket once, and the lists equal the brute force's.
#[test]
fn slot_tasks_tile_the_table_around_a_crowded_bucket() {
    let mut rng = signed(31);
    let (crowd, n) = (5 * SLOTS_PER_TASK / 2, 5 * SLOTS_PER_TASK / 2 + 900);
    let p: [Vec<f32>; 3] = std::array::from_fn(|_| {
        (0..n)
            .map(|i| if i < crowd { 0.505 + 0.002 * rng() } else { 0.5 * rng() })
            .collect()
    });
    let rest: [Vec<f32>; 3] = std::array::from_fn(|k| (0..n).map(|i| ((i * (k + 3)) % 89) as f32 * 0.01).collect());
    let cloth: Vec<u32> = (0..n as u32).map(|i| i % 2).collect();
    let mut h = SpatialHash::new(n);
    h.build(&p[0], &p[1], &p[2], n, 0.01).unwrap();
    let tasks = h.cell_entries.len().div_ceil(SLOTS_PER_TASK);
    let ranges: Vec<_> = (0..tasks).map(|t| h.task_buckets(t, tasks)).collect();
    assert_eq!(ranges[0].start, 0);
    assert_eq!(ranges[tasks - 1].end, h.table_size);
    assert!(ranges.windows(2).all(|w| w[0].end == w[1].start), "{ranges:?}");
    assert!(ranges.iter().any(|r| r.is_empty()), "a task inside the crowded bucket: {ranges:?}");
    let s = (p, rest, cloth);
    assert!(check(&s, 0.01, 0.01, 0.02) > crowd * crowd / 4);
}

/// Cells of `member_spacing` make particles on the cells' faces members of their cells (a flat
/// lattice at `z = 0`, every third column on `x = k reach`); cells exactly the reach wide
/// leave all of them out.
#[test]
fn member_spacing_makes_particles_on_faces_members() {
    let (reach, n) = (0.03f32, 400);
    let x: Vec<f32> = (0..n).map(|i| (i % 20) as f32 * 0.01 - 0.09).collect();
    let y: Vec<f32> = (0..n).map(|i| (i / 20) as f32 * 0.01 + 0.005).collect();
    let z = vec![0.0f32; n];
    let members = |spacing: f32| {
        let mut h = SpatialHash::new(n);
        h.build(&x, &y, &z, n, spacing).unwrap();
        let r = search_radius(reach);
        (0..n).filter(|&k| h.member(k, h.cell_of_slot(k), r)).count()
    };
    assert_eq!(members(SpatialHash::member_spacing(reach)), n);
    assert_eq!(members(reach), 0);
}

/// A value for an injected coordinate: non-finite, saturating, on a cell face or signed zero.
fn special(k: u8, h: f32) -> f32 {
    [f32::NAN, f32::INFINITY, -1e30, 3.0 * h, -0.0, 6.0 * h][k as usize % 6]
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]
    /// On random crumpled pairs of lattices (noise and lift of up to one and a half spacings,
    /// so buckets overflow a lane group and layers interleave) with a few coordinates replaced
    /// by specials, the lanes' member test answers every slot as the scalar one, and every form
    /// of the cell query (lanes and scalar, serial and parallel) equals the brute force, for
    /// cells as wide as the reach or wider and a skip below or above it.
    #[test]
    fn cell_query_lanes_and_scalar_equal_the_brute_force_on_random_lattices(
        side in 3usize..13,
        noise in 0.0f32..1.5,
        lift in 0.0f32..1.5,
        seed in proptest::prelude::any::<u64>(),
        wide in proptest::prelude::any::<bool>(),
        skip in 0.5f32..4.0,
        specials in proptest::collection::vec((proptest::prelude::any::<u16>(), 0u8..3, proptest::prelude::any::<u8>()), 0..4),
    ) {
        let h = 0.01f32;
        let mut s = lattices(side, h, noise, lift, seed);
        let n = s.2.len();
        for (i, axis, k) in specials {
            s.0[axis as usize][i as usize % n] = special(k, h);
        }
        let reach = 3.0 * h;
        let spacing = if wide { 1.5 * reach } else { reach };
        check(&s, spacing, reach, skip * h);
        let (p, rest, cloth) = &s;
        let mut hs = SpatialHash::new(n);
        hs.build(&p[0], &p[1], &p[2], n, spacing).unwrap();
        hs.attach_rest([&rest[0], &rest[1], &rest[2]], cloth).unwrap();
        assert_member_lanes(&hs, search_radius(reach));
    }
}
