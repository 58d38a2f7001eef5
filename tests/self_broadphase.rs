//! Self-collision broadphase: the spatial hash, the particle tree and the brute force must give
//! the same neighbour lists, bit for bit, serial or parallel, on 1 or 2 threads.

use proptest::prelude::*;
use weft::self_collision::hash::SpatialHash;
use weft::self_collision::neighbours::Neighbours;
use weft::self_collision::tree::{ParticleTree, TreeShape};

/// A point cloud as three arrays.
#[derive(Debug, Clone)]
struct Cloud {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
}

impl Cloud {
    fn n(&self) -> usize {
        self.x.len()
    }
}

/// One generated point: uniform, on the cell lattice, in a tight cluster, or a copy of an
/// earlier point (coincident).
fn point_kinds(spacing: f32) -> impl Strategy<Value = (u8, [f32; 3], [i32; 3], usize)> {
    let _ = spacing;
    (
        0u8..4,
        prop::array::uniform3(-4.0f32..4.0),
        prop::array::uniform3(-8i32..8),
        any::<usize>(),
    )
}

fn cloud(spacing: f32) -> impl Strategy<Value = Cloud> {
    prop::collection::vec(point_kinds(spacing), 0..300).prop_map(move |pts| {
        let centres = [[0.0f32, 0.0, 0.0], [-2.5, 1.0, 0.5], [1.7, -3.2, -1.1]];
        let mut c = Cloud {
            x: vec![],
            y: vec![],
            z: vec![],
        };
        for (k, (kind, u, l, pick)) in pts.into_iter().enumerate() {
            let p = match kind {
                0 => u,
                // Exactly on cell boundaries (spacing is a power of two or not, both occur).
                1 => [l[0] as f32 * spacing, l[1] as f32 * spacing, l[2] as f32 * spacing],
                2 => {
                    let ctr = centres[pick % 3];
                    [ctr[0] + u[0] * 0.01, ctr[1] + u[1] * 0.01, ctr[2] + u[2] * 0.01]
                }
                _ if k > 0 => {
                    let j = pick % k;
                    [c.x[j], c.y[j], c.z[j]]
                }
                _ => u,
            };
            c.x.push(p[0]);
            c.y.push(p[1]);
            c.z.push(p[2]);
        }
        c
    })
}

fn setup() -> impl Strategy<Value = (f32, f32, Cloud)> {
    (
        prop::sample::select(vec![0.25f32, 0.5, 1.0, 0.3, 0.7]),
        prop::sample::select(vec![1.0f32, 0.999, 0.5, 0.25, 0.0, 0.618]),
    )
        .prop_flat_map(|(s, frac)| (Just(s), Just(s * frac), cloud(s)))
}

fn brute(c: &Cloud, d: f32) -> Neighbours {
    let mut nb = Neighbours::new();
    nb.fill_brute_force(&c.x, &c.y, &c.z, c.n(), d).unwrap();
    nb
}

fn hash_query(c: &Cloud, s: f32, d: f32) -> (SpatialHash, Neighbours) {
    let mut h = SpatialHash::new(c.n());
    h.build(&c.x, &c.y, &c.z, c.n(), s).unwrap();
    let mut nb = Neighbours::new();
    h.query_all(&c.x, &c.y, &c.z, c.n(), d, &mut nb).unwrap();
    (h, nb)
}

fn tree_query(c: &Cloud, shape: TreeShape, d: f32) -> (ParticleTree, Neighbours) {
    let t = ParticleTree::build(&c.x, &c.y, &c.z, c.n(), shape).unwrap();
    let mut nb = Neighbours::new();
    t.query_all(&c.x, &c.y, &c.z, c.n(), d, &mut nb).unwrap();
    (t, nb)
}

proptest! {
    /// hash == brute force == tree (two shapes), and each serial twin equals its parallel kernel
    /// bitwise (hash tables included).
    #[test]
    fn hash_tree_and_brute_force_agree((s, d, c) in setup(), leaf in 1u32..20) {
        let n = c.n();
        let reference = brute(&c, d);
        let (h, hn) = hash_query(&c, s, d);
        prop_assert_eq!(&hn, &reference);

        let mut hs = SpatialHash::new(0);
        hs.build_serial(&c.x, &c.y, &c.z, n, s).unwrap();
        prop_assert_eq!(hs.cell_start(), h.cell_start());
        prop_assert_eq!(hs.cell_entries(), h.cell_entries());
        let mut hsn = Neighbours::new();
        hs.query_all_serial(&c.x, &c.y, &c.z, n, d, &mut hsn).unwrap();
        prop_assert_eq!(&hsn, &reference);

        for shape in [TreeShape::LeafSize(leaf), TreeShape::Depth(5)] {
            let (t, tn) = tree_query(&c, shape, d);
            prop_assert_eq!(&tn, &reference);
            let mut tsn = Neighbours::new();
            t.query_all_serial(&c.x, &c.y, &c.z, n, d, &mut tsn).unwrap();
            prop_assert_eq!(&tsn, &reference);
        }
        // Every pair once, i < j, symmetric lists.
        for (i, j) in reference.pairs() {
            prop_assert!(i < j);
            prop_assert!(reference.of(j as usize).binary_search(&i).is_ok());
        }
    }

    /// After the points move, refit (parallel and serial, identical boxes) + query still equals
    /// the brute force, with the topology of the old positions.
    #[test]
    fn refit_after_moving_equals_brute_force(
        (s, d, c) in setup(),
        moves in prop::collection::vec(prop::array::uniform3(-2.0f32..2.0), 300),
        leaf in 1u32..12,
    ) {
        let n = c.n();
        let mut t = ParticleTree::build(&c.x, &c.y, &c.z, n, TreeShape::LeafSize(leaf)).unwrap();
        let mut m = c.clone();
        // Move about half of the points, some far.
        for (i, mv) in moves.iter().enumerate().take(n).step_by(2) {
            m.x[i] += mv[0];
            m.y[i] += mv[1];
            m.z[i] += mv[2];
        }
        let mut ts = t.clone();
        t.refit(&m.x, &m.y, &m.z, n).unwrap();
        ts.refit_serial(&m.x, &m.y, &m.z, n).unwrap();
        prop_assert_eq!(t.boxes(), ts.boxes());
        let mut tn = Neighbours::new();
        t.query_all(&m.x, &m.y, &m.z, n, d, &mut tn).unwrap();
        prop_assert_eq!(&tn, &brute(&m, d));
        // Reusing the hash and the lists for the moved points gives the same answer.
        let (mut h, mut hn) = hash_query(&c, s, d);
        h.build(&m.x, &m.y, &m.z, n, s).unwrap();
        h.query_all(&m.x, &m.y, &m.z, n, d, &mut hn).unwrap();
        prop_assert_eq!(&hn, &tn);
    }
}

/// Runs `f` on a rayon pool of `k` threads.
fn on_threads<R: Send>(k: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new().num_threads(k).build().unwrap().install(f)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// 1 thread and 2 threads give identical hash tables, tree boxes and lists.
    #[test]
    fn one_and_two_threads_identical((s, d, c) in setup()) {
        let n = c.n();
        let run = || {
            let (h, hn) = hash_query(&c, s, d);
            let (mut t, _) = tree_query(&c, TreeShape::LeafSize(4), d);
            t.refit(&c.x, &c.y, &c.z, n).unwrap();
            let mut tn = Neighbours::new();
            t.query_all(&c.x, &c.y, &c.z, n, d, &mut tn).unwrap();
            (h.cell_start().to_vec(), h.cell_entries().to_vec(), hn, t.boxes().to_vec(), tn)
        };
        let one = on_threads(1, run);
        let two = on_threads(2, run);
        prop_assert!(one == two);
    }
}

#[test]
fn large_cloud_threads_and_twins_identical() {
    // Enough particles for many parallel chunks: a folded 60x60 sheet with layers s/2 apart.
    let (w, s) = (60usize, 0.1f32);
    let mut c = Cloud {
        x: vec![],
        y: vec![],
        z: vec![],
    };
    for v in 0..w {
        for u in 0..w {
            let (layer, t) = (u / 15, (u % 15) as f32);
            let xu = if layer % 2 == 0 { t } else { 14.0 - t };
            c.x.push(xu * s);
            c.y.push(v as f32 * s);
            c.z.push(layer as f32 * 0.5 * s + 0.001 * ((u * 7 + v * 3) % 5) as f32);
        }
    }
    let reference = brute(&c, s);
    let one = on_threads(1, || hash_query(&c, s, s).1);
    let two = on_threads(2, || hash_query(&c, s, s).1);
    let tree = on_threads(2, || tree_query(&c, TreeShape::LeafSize(8), s).1);
    assert!(reference.total() > 0);
    assert_eq!(one, reference);
    assert_eq!(two, reference);
    assert_eq!(tree, reference);
}

#[test]
fn non_finite_particles_have_no_neighbours() {
    let c = Cloud {
        x: vec![0.0, 0.1, f32::NAN, 0.0, f32::INFINITY, 0.05],
        y: vec![0.0, 0.0, 0.0, f32::NEG_INFINITY, 0.0, 0.0],
        z: vec![0.0; 6],
    };
    let reference = brute(&c, 0.2);
    let (h, hn) = hash_query(&c, 0.2, 0.2);
    assert_eq!(h.non_finite(), 3);
    assert_eq!(hn, reference);
    assert_eq!(hn.of(0), &[1, 5]);
    for i in [2, 3, 4] {
        assert!(hn.of(i).is_empty());
    }
    assert_eq!(tree_query(&c, TreeShape::LeafSize(1), 0.2).1, reference);
}

#[test]
fn far_coordinates_fall_back_and_stay_exact() {
    // Cells far thinner than the f32 spacing of the coordinates, and values near f32::MAX.
    let c = Cloud {
        x: vec![1.0e9, 1.0e9 + 64.0, 1.0e9, f32::MAX, f32::MAX, -f32::MAX, 0.0],
        y: vec![0.0, 0.0, 1.0e-3, 0.0, 0.0, 0.0, 0.0],
        z: vec![0.0; 7],
    };
    for d in [1.0e-3f32, 1.0e-4] {
        let reference = brute(&c, d);
        assert_eq!(hash_query(&c, 1.0e-3, d).1, reference);
        assert_eq!(tree_query(&c, TreeShape::LeafSize(2), d).1, reference);
    }
    assert_eq!(brute(&c, 1.0e-3).of(0), &[2]);
    assert_eq!(brute(&c, 1.0e-3).of(3), &[4]);
    // Spacing so small that the rounding margin spans many cells: the per-particle fallback.
    let t = Cloud {
        x: vec![0.0, 1.0e-20, 5.0e-20, 3.0e-19, -1.0e-20],
        y: vec![0.0; 5],
        z: vec![0.0; 5],
    };
    let reference = brute(&t, 1.0e-20);
    assert_eq!(reference.of(0), &[1, 4]);
    assert_eq!(hash_query(&t, 1.0e-20, 1.0e-20).1, reference);
    assert_eq!(tree_query(&t, TreeShape::LeafSize(1), 1.0e-20).1, reference);
    // Squares that underflow: 1e-23² rounds to 0 <= (1e-30)² = 0, so the predicate calls these
    // neighbours although they are 1e7 max_dists apart; the search margin must find them.
    let u = Cloud {
        x: vec![0.0, 1.0e-23, 1.0],
        y: vec![0.0; 3],
        z: vec![0.0; 3],
    };
    let reference = brute(&u, 1.0e-30);
    assert_eq!(reference.of(0), &[1]);
    assert_eq!(hash_query(&u, 1.0e-30, 1.0e-30).1, reference);
    assert_eq!(tree_query(&u, TreeShape::LeafSize(1), 1.0e-30).1, reference);
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let a = [0.0f32, 1.0, 2.0];
    let mut h = SpatialHash::new(3);
    for s in [0.0, -1.0, f32::NAN, f32::INFINITY, 1.0e-40] {
        assert!(h.build(&a, &a, &a, 3, s).is_err(), "spacing {s}");
    }
    assert!(h.build(&a, &a, &a[..2], 3, 1.0).is_err());
    h.build(&a, &a, &a, 3, 1.0).unwrap();
    let mut nb = Neighbours::new();
    assert!(h.query_all(&a, &a, &a, 3, 1.5, &mut nb).is_err());
    assert!(h.query_all(&a, &a, &a, 3, -0.5, &mut nb).is_err());
    assert!(h.query_all(&a, &a, &a, 2, 0.5, &mut nb).is_err());
    assert!(ParticleTree::build(&a, &a, &a, 3, TreeShape::Depth(21)).is_err());
    assert!(ParticleTree::build(&a, &a, &a, 3, TreeShape::LeafSize(0)).is_err());
    assert!(ParticleTree::build(&a, &a, &a, 4, TreeShape::LeafSize(1)).is_err());
    let mut t = ParticleTree::build(&a, &a, &a, 3, TreeShape::LeafSize(1)).unwrap();
    assert_eq!(t.depth(), 2);
    assert!(t.refit(&a, &a, &a, 2).is_err());
    assert!(t.query_all(&a, &a, &a, 3, f32::NAN, &mut nb).is_err());
    // Positions that moved since the build / refit are refused, not silently misused.
    let moved = [0.0f32, 1.0, 2.5];
    assert!(h.query_all(&moved, &a, &a, 3, 0.5, &mut nb).is_err());
    assert!(h.query_all_serial(&moved, &a, &a, 3, 0.5, &mut nb).is_err());
    assert!(t.query_all(&moved, &a, &a, 3, 0.5, &mut nb).is_err());
    assert!(t.query_all_serial(&moved, &a, &a, 3, 0.5, &mut nb).is_err());
    t.refit(&moved, &a, &a, 3).unwrap();
    assert!(t.query_all(&moved, &a, &a, 3, 0.5, &mut nb).is_ok());
}

#[test]
fn warm_queries_do_not_reallocate() {
    let n = 2000;
    let x: Vec<f32> = (0..n).map(|i| (i % 50) as f32 * 0.125).collect();
    let y: Vec<f32> = (0..n).map(|i| (i / 50) as f32 * 0.125).collect();
    let z = vec![0.0f32; n];
    let mut h = SpatialHash::new(n);
    let mut nb = Neighbours::new();
    h.build(&x, &y, &z, n, 0.125).unwrap();
    h.query_all(&x, &y, &z, n, 0.125, &mut nb).unwrap();
    let (p_first, p_ids) = (nb.first.as_ptr(), nb.ids.as_ptr());
    let entries = h.cell_entries().as_ptr();
    for _ in 0..3 {
        h.build(&x, &y, &z, n, 0.125).unwrap();
        h.query_all(&x, &y, &z, n, 0.125, &mut nb).unwrap();
    }
    assert_eq!((nb.first.as_ptr(), nb.ids.as_ptr()), (p_first, p_ids));
    assert_eq!(h.cell_entries().as_ptr(), entries);
    // An interior grid point has its 4 axis neighbours; the diagonal ones are too far.
    assert_eq!(nb.of(51 + 50), &[51, 100, 102, 151]);
}
