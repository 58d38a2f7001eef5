//! The step's pass (lists built once a step, rest neighbours dropped, contacts added in list
//! order, the correction on the touched blocks) against a recomputation from scratch: the pair
//! sums of a brute force over all pairs with the same rules, and the correction kernel run on
//! every particle. Bit for bit, for the three responses, SIMD and scalar, serial and parallel
//! on one and two threads.

use super::*;
use crate::data::exec::Exec;
use crate::self_collision::response::{apply, ApplyInput, Record, RECORD};
use crate::test_rng::signed;

/// A `rows x cols` cloth of spacing `s` folded in half across a row (second layer `gap` above),
/// each coordinate jittered by up to `jitter`.
fn folded(rows: usize, cols: usize, s: f32, gap: f32, jitter: f32, rng: &mut impl FnMut() -> f32) -> (SelfCollisionData, [Vec<f32>; 3]) {
    let mut data = SelfCollisionData::default();
    let rest: Vec<[f32; 3]> = (0..rows * cols)
        .map(|i| [(i % cols) as f32 * s, 0.0, (i / cols) as f32 * s])
        .collect();
    data.add_cloth(&rest, 0, s, s);
    let mut x = [vec![0.0f32; rows * cols], vec![0.0; rows * cols], vec![0.0; rows * cols]];
    for r in 0..rows {
        for c in 0..cols {
            let i = r * cols + c;
            let (y, z) = if r < rows / 2 {
                (0.0, r as f32 * s)
            } else {
                (gap, (rows - 1 - r) as f32 * s)
            };
            let p = [c as f32 * s, y, z];
            for a in 0..3 {
                x[a][i] = p[a] + jitter * rng();
            }
        }
    }
    (data, x)
}

fn padded(v: &[f32]) -> Vec<f32> {
    let mut p = v.to_vec();
    p.resize(crate::data::lanes::round_up(v.len() + 1), 0.0);
    p
}

/// Runs one pair pass and one correction; returns `(p after, sums by particle)`.
#[allow(clippy::type_complexity)]
fn compact(
    data: &mut SelfCollisionData,
    x: &[Vec<f32>; 3],
    p: &[Vec<f32>; 3],
    w: &[f32],
    n: usize,
    exec: Exec,
) -> ([Vec<f32>; 3], Vec<[f32; 11]>) {
    let damping = vec![0.8f32; n];
    let xs = [&x[0][..], &x[1][..], &x[2][..]];
    assert!(data.begin_step(xs, n, &damping, crate::data::exec::Exec::Parallel).unwrap());
    let mut out = p.clone();
    // VcCPBD's box centres (the other responses read none).
    if let Some(sink) = data.prediction_sink(false) {
        sink.keep(0, [&out[0][..], &out[1][..], &out[2][..]]);
    }
    data.pair_pass(xs, [&p[0][..], &p[1][..], &p[2][..]], w, exec);
    // The sums before the correction reads (and zeroes) them.
    let mut by_particle = data.state.as_ref().unwrap().pass.sums();
    by_particle.truncate(n);
    let a = data.active().unwrap();
    let ap = a.apply_params(0.005);
    let [o0, o1, o2] = &mut out;
    data.apply(xs, w, None, [o0, o1, o2], ap, exec);
    assert!(
        data.state
            .as_ref()
            .unwrap()
            .pass
            .sums()
            .iter()
            .all(|s| s.iter().all(|v| v.to_bits() == 0)),
        "the correction leaves every record zero"
    );
    (out, by_particle)
}

/// Particle positions, one array a coordinate.
type Positions = [Vec<f32>; 3];

/// Asserts two passes' results equal bit for bit: every particle's sums and, when given, its
/// positions after the correction (`(got, want)`).
fn assert_same_bits(got: &[[f32; 11]], want: &[[f32; 11]], p: Option<(&Positions, &Positions)>, n: usize, what: &str) {
    for i in 0..n {
        assert_eq!(got[i].map(f32::to_bits), want[i].map(f32::to_bits), "{what}: sums of {i}");
        if let Some((gp, wp)) = p {
            for a in 0..3 {
                assert_eq!(gp[a][i].to_bits(), wp[a][i].to_bits(), "{what}: p of {i}");
            }
        }
    }
}

/// The pair context of the reference: the start and predicted positions `x`, `p` and inverse
/// masses `w` with the data's rest records and active settings.
fn reference_ctx<'a>(data: &'a SelfCollisionData, x: &'a [Vec<f32>; 3], p: &'a [Vec<f32>; 3], w: &'a [f32]) -> PairCtx<'a> {
    let a = data.active().unwrap();
    PairCtx {
        x: [&x[0], &x[1], &x[2]],
        p: [&p[0], &p[1], &p[2]],
        w,
        rest4: &data.rest4,
        d: a.d,
        response: a.response,
    }
}

/// Pairs in contact by the reference's one-sided test, tried from each free end (every pair
/// tested, rest rule applied): what the pass's contact count must be.
fn reference_contacts(data: &SelfCollisionData, x: &[Vec<f32>; 3], p: &[Vec<f32>; 3], w: &[f32], n: usize) -> usize {
    let a = data.active().unwrap();
    let ctx = reference_ctx(data, x, p, w);
    let adds = |i: usize, j: usize| {
        let (mut out, mut approaching) = ([0.0f32; 11], 0.0f32);
        ctx.add_contact(i, j, &mut out, &mut approaching);
        out[10] > 0.0
    };
    (0..n)
        .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
        .filter(|&(i, j)| !data.rest_data().skipped(i, j, a.skip) && (adds(i, j) || adds(j, i)))
        .count()
}

/// The reference: every pair tested (no broadphase, rest rule applied), the kernel run on all
/// particles.
#[allow(clippy::type_complexity)]
fn reference(data: &SelfCollisionData, x: &[Vec<f32>; 3], p: &[Vec<f32>; 3], w: &[f32], n: usize) -> ([Vec<f32>; 3], Vec<[f32; 11]>) {
    let a = data.active().unwrap();
    let mut all = Neighbours::new();
    all.fill_serial(n, |i, buf| {
        buf.extend(
            (0..n)
                .filter(|&j| j != i && !data.rest_data().skipped(i, j, a.skip))
                .map(|j| j as u32),
        )
    })
    .unwrap();
    let ctx = reference_ctx(data, x, p, w);
    let sums: Vec<[f32; 11]> = (0..n).map(|i| ctx.sums(&all, i)).collect();
    // The records of the sums (the corrections already over the approaching contacts: no
    // approaching count left to rescale by).
    let mut full: Vec<Record> = vec![[0.0; RECORD]; p[0].len()];
    for (r, v) in full.iter_mut().zip(&sums) {
        r[..11].copy_from_slice(v);
    }
    let damping = padded(&vec![0.8f32; n]);
    let mut out = p.clone();
    let inp = ApplyInput {
        start: 0,
        x: [&x[0], &x[1], &x[2]],
        w,
        q: [&p[0], &p[1], &p[2]],
        v: None,
        b: &damping,
        sums: &full,
        friction: a.friction,
        h: 0.005,
        r: BOX_RADIUS * a.d,
    };
    let [o0, o1, o2] = &mut out;
    apply(&inp, [o0, o1, o2], a.response, false);
    (out, sums)
}

#[test]
fn compact_step_equals_recomputation_from_scratch() {
    let mut rng = signed(7);
    let (rows, cols, s) = (14, 11, 0.02f32);
    for case in 0..6 {
        let response = [Response::Pbd, Response::MovementSpeed, Response::Vccpbd][case % 3];
        let (mut data, x0) = folded(rows, cols, s, 1.05 * s, 0.3 * s, &mut rng);
        data.config = Some(SelfCollision {
            response,
            ..SelfCollision::default()
        });
        let n = rows * cols;
        let x = [padded(&x0[0]), padded(&x0[1]), padded(&x0[2])];
        // Predicted positions within one travel `T = d` of the start (what the clamp allows).
        let mut p = x.clone();
        for c in &mut p {
            for v in &mut c[..n] {
                *v += 0.55 * s * rng();
            }
        }
        let mut w = padded(&vec![1.0f32; n]);
        w[case] = 0.0;
        let (want_p, want_sums) = reference(&data, &x, &p, &w, n);
        assert!(want_sums.iter().any(|v| v[10] > 0.0), "case {case}: no contact to compare");
        for (parallel, simd) in [(false, false), (false, true), (true, true), (true, false)] {
            for threads in [1, 2] {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                let (got_p, got_sums) = pool.install(|| compact(&mut data, &x, &p, &w, n, Exec::new(simd, parallel)));
                let what = format!("case {case} ({parallel}, {simd}, {threads})");
                assert_same_bits(&got_sums, &want_sums, Some((&got_p, &want_p)), n, &what);
            }
        }
        assert!(data.pair_count() > 0);
        // Every run above listed the same pairs and found the same contacts: the means are
        // those of one pass.
        let st = &data.stats;
        assert_eq!(st.pairs_per_step, data.pair_count() as f64, "case {case}");
        let contacts = reference_contacts(&data, &x, &p, &w, n);
        assert!(contacts > 0);
        assert_eq!(st.contacts_per_substep, contacts as f64, "case {case}");
    }
}

#[test]
fn rest_neighbours_are_never_listed() {
    let mut rng = signed(3);
    let (rows, cols, s) = (12, 9, 0.02f32);
    let (mut data, x0) = folded(rows, cols, s, 1.1 * s, 0.0, &mut rng);
    data.config = Some(SelfCollision::default());
    let n = rows * cols;
    let x = [&x0[0][..], &x0[1][..], &x0[2][..]];
    assert!(data.begin_step(x, n, &vec![0.0; n], crate::data::exec::Exec::Parallel).unwrap());
    let lists = data.lists().unwrap();
    let d = data.distance();
    // Fold rows r and rows - 1 - r lie `gap` apart; only rows 3 or more apart at rest are kept.
    assert!(lists.total() > 0);
    assert!(
        (0..n).all(|i| lists.of(i).iter().all(|&j| j as usize > i)),
        "each pair once, under its smaller id"
    );
    for (i, j) in lists.pairs() {
        let (ri, rj) = (i as usize / cols, j as usize / cols);
        assert!(ri.abs_diff(rj) >= 3, "{i} {j}");
        assert!(!data.rest_data().skipped(i as usize, j as usize, REST_SKIP_FACTOR * d));
    }
    // A flat cloth: the step has nothing to do.
    let flat: Vec<f32> = (0..n).map(|i| (i / cols) as f32 * s).collect();
    let zero = vec![0.0; n];
    let xs: Vec<f32> = (0..n).map(|i| (i % cols) as f32 * s).collect();
    assert!(data
        .begin_step([&xs, &zero, &flat], n, &zero, crate::data::exec::Exec::Parallel)
        .unwrap());
    assert_eq!(data.lists().unwrap().total(), 0);
    assert_eq!(data.pair_count(), 0);
}

/// Consecutive pair passes over different predictions (as the substeps run them): after each
/// pass the sums are those of a recomputation for its own predictions, so a particle whose
/// contacts ended has zero sums again, and one still in contact its new sums.
#[test]
fn consecutive_pair_passes_leave_no_stale_sums() {
    let mut rng = signed(13);
    let (rows, cols, s) = (14, 11, 0.02f32);
    let (mut data, x0) = folded(rows, cols, s, 1.05 * s, 0.3 * s, &mut rng);
    data.config = Some(SelfCollision {
        response: Response::Vccpbd,
        ..SelfCollision::default()
    });
    let n = rows * cols;
    let x = [padded(&x0[0]), padded(&x0[1]), padded(&x0[2])];
    let w = padded(&vec![1.0f32; n]);
    let (mut ended, mut kept) = (0, 0);
    let mut last: Option<Vec<[f32; 11]>> = None;
    for pass in 0..6 {
        // Predictions spread less and less: the contact set changes from pass to pass.
        let spread = [0.55, 0.1, 0.4, 0.0, 0.3, 0.05][pass] * s;
        let mut p = x.clone();
        for c in &mut p {
            for v in &mut c[..n] {
                *v += spread * rng();
            }
        }
        let (_, want) = reference(&data, &x, &p, &w, n);
        // Serial and parallel passes alternating (the parallel search fills its chunks'
        // buffers; each pass zeroes the sums the other left).
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        for (parallel, simd) in [(false, false), (true, true), (false, true), (true, false)] {
            let (_, got) = pool.install(|| compact(&mut data, &x, &p, &w, n, Exec::new(simd, parallel)));
            assert_same_bits(&got, &want, None, n, &format!("pass {pass} ({parallel}, {simd})"));
        }
        if let Some(prev) = &last {
            ended += (0..n).filter(|&i| prev[i][10] > 0.0 && want[i][10] == 0.0).count();
            kept += (0..n).filter(|&i| prev[i][10] > 0.0 && want[i][10] > 0.0).count();
        }
        last = Some(want);
    }
    assert!(ended > 0 && kept > 0, "{ended} ended, {kept} kept contacts");
}

/// A folded `rows x cols` cloth (spacing 2 cm, layers 1.02 spacings apart, jittered) with the
/// default settings, and predictions within half a spacing of the start: `(data, x, p, w, n)`.
#[allow(clippy::type_complexity)]
fn jittered_fold(rows: usize, cols: usize, seed: u64) -> (SelfCollisionData, [Vec<f32>; 3], [Vec<f32>; 3], Vec<f32>, usize) {
    let mut rng = signed(seed);
    let s = 0.02f32;
    let (mut data, x0) = folded(rows, cols, s, 1.02 * s, 0.3 * s, &mut rng);
    data.config = Some(SelfCollision::default());
    let n = rows * cols;
    let x = [padded(&x0[0]), padded(&x0[1]), padded(&x0[2])];
    let mut p = x.clone();
    for c in &mut p {
        for v in &mut c[..n] {
            *v += 0.5 * s * rng();
        }
    }
    let w = padded(&vec![1.0f32; n]);
    (data, x, p, w, n)
}

/// The correction pass over the touched blocks in parallel (1 and 2 threads, several groups
/// of blocks) gives the bits of the serial runs (the step asks for it only from
/// `APPLY_PARALLEL_BLOCKS` touched blocks).
#[test]
fn parallel_correction_equals_serial() {
    let (mut data, x, p, w, n) = jittered_fold(200, 60, 21);
    let (want, _) = compact(&mut data, &x, &p, &w, n, Exec::Simd);
    let touched = data.touched_blocks();
    // Enough for the parallel form, in several groups of blocks.
    assert!(
        touched >= crate::self_collision::pass::APPLY_PARALLEL_BLOCKS,
        "{touched} touched blocks"
    );
    let ap = data.active().unwrap().apply_params(0.005);
    let xs = [&x[0][..], &x[1][..], &x[2][..]];
    // The pair pass again (its correction in `compact` zeroed the records): the same sums.
    data.pair_pass(xs, [&p[0][..], &p[1][..], &p[2][..]], &w, Exec::Simd);
    let st = data.state.as_ref().unwrap();
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let mut got = p.clone();
        let [g0, g1, g2] = &mut got;
        // A copy of the pass: the correction zeroes the records it reads.
        let mut pass = st.pass.clone();
        pool.install(|| pass.apply(xs, &w, None, [g0, g1, g2], ap, Exec::Parallel));
        for a in 0..3 {
            assert!(
                got[a].iter().zip(&want[a]).all(|(u, v)| u.to_bits() == v.to_bits()),
                "{threads} threads"
            );
        }
        assert_ne!(got, p, "the correction moved particles");
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
    /// The eight-lane contact test equals its scalar twin on random lists (runs of one `i`
    /// and mixed groups, lengths around the lane width and the chunk size), and finds exactly
    /// the pairs closer than the margin of `d` (the scalar decision, written out here).
    #[test]
    fn touching_lanes_equal_the_scalar_test(n in 2usize..300, pairs in 0usize..5000, seed in proptest::prelude::any::<u64>()) {
        let mut rng = signed(seed | 1);
        let p: [Vec<f32>; 3] = std::array::from_fn(|_| (0..n).map(|_| 0.05 * rng()).collect());
        let xyzw: Vec<[f32; 4]> = (0..n).map(|i| [p[0][i], p[1][i], p[2][i], 0.0]).collect();
        // CSR lists of random upper partners, some particles with long runs.
        let mut first = vec![0u32];
        let mut ids = Vec::new();
        for i in 0..n - 1 {
            let k = if rng() > 0.6 { (pairs / n).min(n - 1 - i) } else { ((rng() + 1.0) * 3.0) as usize % (n - i) };
            let mut js: Vec<u32> = (0..k).map(|_| (i + 1 + ((rng() + 1.0) * 0.5 * (n - i - 1) as f32) as usize).min(n - 1) as u32).collect();
            js.sort_unstable();
            js.dedup();
            ids.extend(js);
            first.push(ids.len() as u32);
        }
        first.push(ids.len() as u32);
        let mut rows = PairRows::default();
        rows.fill(&first, &ids);
        let list = rows.list(&ids);
        let w = vec![1.0; n];
        let ctx = PairCtx {
            x: [&p[0], &p[1], &p[2]],
            p: [&p[0], &p[1], &p[2]],
            w: &w,
            rest4: &[],
            d: 0.03,
            response: Response::Pbd,
        };
        let (mut lanes, mut scalar) = (Vec::new(), Vec::new());
        for start in (0..list.len()).step_by(1000) {
            let r = start..(start + 1000).min(list.len());
            ctx.touching(list, r.clone(), &xyzw, true, &mut lanes);
            ctx.touching(list, r, &xyzw, false, &mut scalar);
        }
        proptest::prop_assert_eq!(&lanes, &scalar);
        let lim = 0.03f32 * 0.03 * 1.0001;
        let want: Vec<(u32, u32)> = list.i.iter().zip(list.j).map(|(&i, &j)| (i, j)).filter(|&(i, j)| {
            let v: [f32; 3] = std::array::from_fn(|a| p[a][i as usize] - p[a][j as usize]);
            v[0] * v[0] + v[1] * v[1] + v[2] * v[2] < lim
        }).collect();
        proptest::prop_assert_eq!(&lanes, &want);
    }
}

/// Contacts found in parallel over many chunks of the list and added afterwards on one thread:
/// the sums and corrected positions equal the serial scalar pass's bit for bit, on 2 and 3
/// threads, and the pass counts each contact once.
#[test]
fn contacts_found_in_parallel_chunks_equal_the_serial_pass() {
    let (mut data, x, p, w, n) = jittered_fold(160, 50, 31);
    let (want_p, want) = compact(&mut data, &x, &p, &w, n, Exec::Scalar);
    let contacts: f32 = want.iter().map(|v| v[10]).sum::<f32>() / 2.0;
    let pairs = data.state.as_ref().unwrap().lists.total();
    assert!(
        contacts >= 2000.0 && pairs > 4 * crate::self_collision::pass::PAIR_CHUNK,
        "{contacts} contacts, {pairs} pairs"
    );
    let counted = data.state.as_ref().unwrap().pass.contacts();
    assert_eq!(counted, reference_contacts(&data, &x, &p, &w, n));
    for threads in [2, 3] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let (got_p, got) = pool.install(|| compact(&mut data, &x, &p, &w, n, Exec::Parallel));
        assert_same_bits(&got, &want, Some((&got_p, &want_p)), n, &format!("{threads} threads"));
        assert_eq!(data.state.as_ref().unwrap().pass.contacts(), counted, "{threads} threads");
    }
}
