//! The per-particle contact sums the pair pass leaves for the velocity correction
//! ([`crate::self_collision::response`]): eleven arrays padded to the lane width, written a
//! block of eight particles at a time from the records one part of the particles adds its
//! contacts into ([`PartSums`]).

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
    /// The rows `..at` and `at..` (`at` clamped to the length), for parts written in parallel.
    pub(crate) fn split_at(self, at: usize) -> (SumRows<'a>, SumRows<'a>) {
        let at = at.min(self.len);
        let mut lo: [&'a mut [f32]; 11] = Default::default();
        let mut hi: [&'a mut [f32]; 11] = Default::default();
        for ((a, l), h) in self.a.into_iter().zip(&mut lo).zip(&mut hi) {
            (*l, *h) = a.split_at_mut(at);
        }
        (SumRows { len: at, a: lo }, SumRows { len: self.len - at, a: hi })
    }

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
    /// ([`SumRows::set_block`]), split into parts with [`SumRows::split_at`].
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

/// The sums of one part of the particles (whole blocks from `b0`) while its contacts are
/// added in list order (see `ContactPass::pair_pass`).
pub(crate) struct PartSums<'a> {
    b0: usize,
    acc: &'a mut [Record],
    hit: &'a mut [bool],
    /// The part's blocks of the last pass.
    mine: &'a [u32],
    /// Store the touched blocks' sums with lane transposes (else record by record, the twin).
    simd: bool,
    /// Contacts whose `i` the part holds.
    contacts: usize,
}

impl<'a> PartSums<'a> {
    /// Starts the part of blocks from `b0` (as many as `hit` holds), `old` the blocks the last
    /// pass touched (ascending).
    pub(crate) fn begin(b0: usize, acc: &'a mut [Record], hit: &'a mut [bool], old: &'a [u32], simd: bool) -> Self {
        let mine = old.partition_point(|&b| (b as usize) < b0)..old.partition_point(|&b| (b as usize) < b0 + hit.len());
        let mine = &old[mine];
        for &b in mine {
            hit[b as usize - b0] = false;
        }
        PartSums {
            b0,
            acc,
            hit,
            mine,
            simd,
            contacts: 0,
        }
    }

    /// Adds the contacts `found` of the pairs `near` to the sides that belong to the part.
    #[inline]
    pub(crate) fn add(&mut self, near: &[(u32, u32)], found: &[Option<PairContact>]) {
        let first_id = self.b0 * LANES;
        for (&(i, j), contact) in near.iter().zip(found) {
            let Some(c) = contact else { continue };
            for (side, a) in [(0, i as usize), (1, j as usize)] {
                let Some(rec) = a.checked_sub(first_id).and_then(|k| self.acc.get_mut(k)) else {
                    continue;
                };
                // Each contact counted once, by the part that holds its `i`.
                self.contacts += usize::from(side == 0);
                if c.add_to(side, rec) {
                    self.hit[(a - first_id) / LANES] = true;
                }
            }
        }
    }

    /// Zeroes the last pass's blocks this one did not touch, stores the sums of the touched
    /// blocks into `rows` (the part's) and lists them in `touched`; returns the part's
    /// contacts.
    pub(crate) fn finish(self, mut rows: SumRows<'_>, touched: &mut Vec<u32>) -> usize {
        let b0 = self.b0;
        for &b in self.mine {
            if !self.hit[b as usize - b0] {
                rows.set_block(b as usize - b0, |_| [0.0; 11]);
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
            touched.push((b0 + b) as u32);
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
        /// block of a part's rows; a block past the rows is ignored by both.
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
