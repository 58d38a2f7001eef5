//! Tests of the neighbour lists (CSR form, fills, helpers).

use super::limit::METER_BATCH;
use super::*;

#[test]
fn brute_force_small_case_and_accessors() {
    // 0 and 1 at distance 1, 2 coincides with 0, 3 is far, 4 is NaN.
    let x = [0.0, 1.0, 0.0, 10.0, f32::NAN];
    let y = [0.0; 5];
    let z = [0.0; 5];
    let mut nb = Neighbours::new();
    nb.fill_brute_force(&x, &y, &z, 5, 1.0).unwrap();
    assert_eq!(nb.len(), 5);
    assert_eq!(nb.of(0), &[1, 2]);
    assert_eq!(nb.of(1), &[0, 2]);
    assert_eq!(nb.of(2), &[0, 1]);
    assert!(nb.of(3).is_empty() && nb.of(4).is_empty());
    assert_eq!(nb.get(5), None);
    assert_eq!(nb.pairs().collect::<Vec<_>>(), vec![(0, 1), (0, 2), (1, 2)]);
    assert_eq!(nb.total(), 6);
    nb.clear();
    assert!(nb.is_empty() && nb.first == vec![0] && nb.ids.is_empty());
}

#[test]
fn sort_dedup_tail_leaves_the_head_alone() {
    let mut v = vec![9, 1, 5, 3, 5, 1, 5];
    sort_dedup_tail(&mut v, 2);
    assert_eq!(v, vec![9, 1, 1, 3, 5]);
}

#[test]
fn bad_inputs_are_errors() {
    let mut nb = Neighbours::new();
    let a = [0.0f32; 3];
    assert!(nb.fill_brute_force(&a, &a, &a, 4, 1.0).is_err());
    assert!(nb.fill_brute_force(&a, &a, &a, 3, -1.0).is_err());
    assert!(nb.fill_brute_force(&a, &a, &a, 3, f32::NAN).is_err());
    assert!(nb.fill_brute_force(&a, &a, &a, 3, 0.0).is_ok());
    // Coincident points are neighbours even at max_dist 0.
    assert_eq!(nb.total(), 6);
}

#[test]
fn parallel_fill_equals_serial_fill() {
    let n = 3 * CHUNK + 17;
    let f = |i: usize, buf: &mut Vec<u32>| {
        for j in (0..(i % 7)).map(|k| ((i * 31 + k * 7) % n) as u32) {
            buf.push(j);
        }
    };
    let mut a = Neighbours::new();
    let mut b = Neighbours::new();
    a.fill_parallel(n, f).unwrap();
    b.fill_serial(n, f).unwrap();
    assert_eq!(a, b);
    // Refill with fewer particles reuses the buffers.
    let cap = a.ids.capacity();
    a.fill_parallel(10, f).unwrap();
    b.fill_serial(10, f).unwrap();
    assert_eq!(a, b);
    assert_eq!(a.ids.capacity(), cap);
}

/// Every fill stops at the limit: the lists come back empty with the error, the writing
/// stopped near the limit (the buffers hold at most the limit plus a batch and one particle's
/// list a thread), and the same fill under the limit succeeds.
#[test]
fn fills_stop_at_the_limit() {
    let n = 4 * CHUNK;
    // Each particle lists 10 others: 10 n entries in all.
    let f = |i: usize, buf: &mut Vec<u32>| buf.extend((1..=10).map(|k| ((i + k) % n) as u32));
    let pairs = |buf: &mut Vec<u32>, meter: &mut Meter<'_>| {
        for i in 0..n as u32 {
            let before = buf.len();
            buf.extend((1..=5).map(|k| [i, i + k]).filter(|p| (p[1] as usize) < n).flatten());
            if !meter.add((buf.len() - before) / 2) {
                return;
            }
        }
    };
    let mut nb = Neighbours::new();
    nb.set_limit(10 * n);
    nb.fill_parallel(n, f).unwrap();
    nb.fill_serial(n, f).unwrap();
    nb.fill_pairs_serial(n, pairs).unwrap();
    assert!(!nb.limited() && nb.total() > 4 * n);
    nb.set_limit(3 * n);
    assert_eq!(nb.limit(), 3 * n);
    let e = nb.fill_parallel(n, f).unwrap_err().to_string();
    assert!(e.contains(&(3 * n).to_string()) && e.contains("3 a particle"), "{e}");
    assert!(nb.limited() && nb.is_empty());
    let written: usize = nb.scratch.iter().map(Vec::len).sum();
    assert!(written <= 3 * n + (METER_BATCH + 10) * rayon::current_num_threads(), "{written}");
    assert!(nb.fill_serial(n, f).is_err() && nb.limited() && nb.is_empty());
    assert!(nb.fill_pairs_serial(n, pairs).is_err() && nb.limited() && nb.is_empty());
    let e = nb.fill_pairs_parallel(n, 8, |t, buf, b| {
        if t == 0 {
            pairs(buf, b)
        }
    });
    assert!(e.is_err() && nb.limited());
    nb.set_limit(usize::MAX);
    assert_eq!(nb.limit(), u32::MAX as usize, "at most the ids' range");
    nb.fill_pairs_parallel(n, 8, |t, buf, b| {
        if t == 0 {
            pairs(buf, b)
        }
    })
    .unwrap();
    assert!(!nb.limited() && nb.total() > 4 * n);
}
