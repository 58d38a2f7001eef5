//! The per-particle contact sums the pair pass leaves for the velocity correction
//! ([`crate::self_collision::response`]): eleven arrays padded to the lane width, written a
//! block of eight particles at a time from the records the pass adds its contacts into
//! ([`Accumulator`]).

use crate::data::lanes::{store, F32s, LANES};
use crate::self_collision::pass::contact::PairContact;
use crate::self_collision::pass::pairs::PairCtx;

/// Values of a particle's [`Record`]: its eleven sums and its approaching count.
pub(crate) const RECORD: usize = 12;

/// A particle's sums `[c(3), f(3), n(3), gap, count]` and approaching count, one record while
/// the pass adds its contacts.
pub(crate) type Record = [f32; RECORD];

/// Per-particle contact sums from the pair pass, padded to the lane width.
#[derive(Clone, Debug, Default)]
pub struct ContactSums {
    /// Position corrections, summed.
    pub c: [Vec<f32>; 3],
    /// Partners' displacements this substep, summed.
    pub f: [Vec<f32>; 3],
    /// Unit contact normals, summed.
    pub n: [Vec<f32>; 3],
    /// Signed gaps `dist - min_dist`, summed.
    pub gap: Vec<f32>,
    /// Number of contacts.
    pub count: Vec<f32>,
}

/// The arrays of a [`ContactSums`] in the order of its eleven-value layout, all `len` long
/// ([`ContactSums::rows`]).
pub(crate) struct SumRows<'a> {
    len: usize,
    a: [&'a mut [f32]; 11],
}

impl<'a> SumRows<'a> {
    /// Stores block `b`'s sums from its eight records (the first eleven values of each). With
    /// `simd`, two 8 x 8 lane transposes (records' values 0..8 and 4..12) and a vector store a
    /// row; else [`SumRows::set_block`] value by value (the twin: the same values either way). A
    /// block past the arrays is ignored.
    #[inline]
    pub(crate) fn set_records(&mut self, b: usize, recs: &[Record], simd: bool) {
        let k = b * LANES;
        if !(simd && recs.len() == LANES && k + LANES <= self.len) {
            self.set_block(b, |l| std::array::from_fn(|c| recs[l][c]));
            return;
        }
        let half = |from: usize| {
            let rows: [F32s; LANES] = std::array::from_fn(|l| {
                let a: [f32; LANES] = recs[l][from..from + LANES].try_into().expect("eight values");
                F32s::from(a)
            });
            F32s::transpose(rows)
        };
        let (lo, hi) = (half(0), half(4));
        for (c, row) in self.a.iter_mut().enumerate() {
            store(row, k, if c < LANES { lo[c] } else { hi[c - 4] });
        }
    }

    /// Stores the rows of block `b` (particles `b * LANES ..`, local to these rows) from
    /// `v(l)` for lane `l`; a block past the arrays is ignored.
    #[inline]
    pub(crate) fn set_block(&mut self, b: usize, v: impl Fn(usize) -> [f32; 11]) {
        let k = b * LANES;
        if k + LANES <= self.len {
            let rows: [[f32; 11]; LANES] = std::array::from_fn(v);
            for (c, a) in self.a.iter_mut().enumerate() {
                for (d, r) in a[k..k + LANES].iter_mut().zip(&rows) {
                    *d = r[c];
                }
            }
        }
    }
}

impl ContactSums {
    /// Sums for `len` particles (a multiple of the lane width), all zero.
    pub fn new(len: usize) -> Self {
        let z = || vec![0.0; len];
        ContactSums {
            c: [z(), z(), z()],
            f: [z(), z(), z()],
            n: [z(), z(), z()],
            gap: z(),
            count: z(),
        }
    }

    /// The eleven arrays cut to their common length, for the pair pass's block stores
    /// ([`SumRows::set_block`]).
    pub(crate) fn rows(&mut self) -> SumRows<'_> {
        let len = self
            .c
            .iter()
            .chain(&self.f)
            .chain(&self.n)
            .chain([&self.gap, &self.count])
            .map(Vec::len)
            .min()
            .unwrap_or(0);
        let [c0, c1, c2] = &mut self.c;
        let [f0, f1, f2] = &mut self.f;
        let [n0, n1, n2] = &mut self.n;
        SumRows {
            len,
            a: [c0, c1, c2, f0, f1, f2, n0, n1, n2, &mut self.gap, &mut self.count].map(|v| &mut v[..len]),
        }
    }

    /// Stores particle `k`'s sums from one array laid out `c (3), f (3), n (3), gap, count`.
    #[inline]
    pub fn set(&mut self, k: usize, v: &[f32; 11]) {
        for a in 0..3 {
            self.c[a][k] = v[a];
            self.f[a][k] = v[3 + a];
            self.n[a][k] = v[6 + a];
        }
        self.gap[k] = v[9];
        self.count[k] = v[10];
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.count.len()
    }

    /// Whether there are no entries.
    pub fn is_empty(&self) -> bool {
        self.count.is_empty()
    }
}

/// The particles' sums while the pass adds its contacts in list order (see
/// `ContactPass::pair_pass`).
pub(crate) struct Accumulator<'a> {
    acc: &'a mut [Record],
    hit: &'a mut [bool],
    /// The blocks of the last pass.
    old: &'a [u32],
    /// Store the touched blocks' sums with lane transposes (else record by record, the twin).
    simd: bool,
    /// Contacts added.
    contacts: usize,
}

impl<'a> Accumulator<'a> {
    /// Starts a pass over the records `acc` and block flags `hit`, `old` the blocks the last
    /// pass touched (ascending).
    pub(crate) fn begin(acc: &'a mut [Record], hit: &'a mut [bool], old: &'a [u32], simd: bool) -> Self {
        for &b in old {
            if let Some(h) = hit.get_mut(b as usize) {
                *h = false;
            }
        }
        Accumulator {
            acc,
            hit,
            old,
            simd,
            contacts: 0,
        }
    }

    /// Adds the contacts `found` of the pairs `near` to both particles' records.
    #[inline]
    pub(crate) fn add(&mut self, near: &[(u32, u32)], found: &[Option<PairContact>]) {
        for (&(i, j), contact) in near.iter().zip(found) {
            let Some(c) = contact else { continue };
            self.contacts += 1;
            for (side, a) in [(0, i as usize), (1, j as usize)] {
                let Some(rec) = self.acc.get_mut(a) else { continue };
                if c.add_to(side, rec) {
                    self.hit[a / LANES] = true;
                }
            }
        }
    }

    /// Zeroes the last pass's blocks this one did not touch, stores the sums of the touched
    /// blocks into `rows` and lists them in `touched`; returns the contacts added.
    pub(crate) fn finish(self, mut rows: SumRows<'_>, touched: &mut Vec<u32>) -> usize {
        for &b in self.old {
            if !self.hit.get(b as usize).copied().unwrap_or(true) {
                rows.set_block(b as usize, |_| [0.0; 11]);
            }
        }
        touched.clear();
        for (b, _) in self.hit.iter().enumerate().filter(|(_, h)| **h) {
            let run = &mut self.acc[b * LANES..(b + 1) * LANES];
            for rec in run.iter_mut() {
                let (out, approaching) = split_record(rec);
                PairCtx::finish(out, *approaching);
            }
            rows.set_records(b, run, self.simd);
            run.fill([0.0; RECORD]);
            touched.push(b as u32);
        }
        self.contacts
    }
}

/// The sums and the approaching count of a record.
#[inline(always)]
fn split_record(rec: &mut Record) -> (&mut [f32; 11], &mut f32) {
    let (out, rest) = rec.split_at_mut(11);
    (out.try_into().expect("eleven sums"), &mut rest[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        /// The touched blocks' sums stored with lane transposes equal the value-by-value store, bit
        /// for bit (signed zeros, NaN payloads and subnormals included, at random places), in every
        /// block of the rows; a block past the rows is ignored by both.
        #[test]
        fn block_records_store_the_same_bits_by_lanes_and_one_by_one(seed in proptest::prelude::any::<u64>(), every in 2usize..20) {
            let mut r = crate::test_rng::signed(seed);
            let specials = [-0.0f32, f32::from_bits(0x7fc0_1234), f32::from_bits(1), f32::INFINITY];
            let len = 5 * LANES;
            let recs: Vec<Record> = (0..len)
                .map(|i| std::array::from_fn(|c| if (i + c) % every == 0 { specials[(i + c) % 4] } else { r() }))
                .collect();
            let store = |simd: bool| {
                let mut s = ContactSums::new(len);
                let mut rows = s.rows();
                for b in 0..=len / LANES {
                    let run = &recs[(b * LANES).min(len - LANES)..][..LANES];
                    rows.set_records(b, run, simd);
                }
                let all = [
                    &s.c[0], &s.c[1], &s.c[2], &s.f[0], &s.f[1], &s.f[2], &s.n[0], &s.n[1], &s.n[2], &s.gap, &s.count,
                ];
                all.iter().flat_map(|a| a.iter().map(|v| v.to_bits())).collect::<Vec<u32>>()
            };
            let lanes = store(true);
            proptest::prop_assert_eq!(&lanes, &store(false));
            // Row `c` of particle `k` holds value `c` of its record.
            for (c, row) in lanes.chunks(len).enumerate() {
                proptest::prop_assert!(row.iter().zip(&recs).all(|(got, rec)| *got == rec[c].to_bits()), "row {}", c);
            }
        }
    }
}
