//! The per-particle contact sums the pair pass leaves for the velocity correction
//! ([`crate::self_collision::response`]): one [`Record`] a particle, padded to whole blocks of
//! eight, added to in list order ([`Accumulator`]) and read, then zeroed, by the correction.

use crate::data::lanes::{F32s, LANES};
use crate::self_collision::pass::contact::PairContact;

/// Values of a particle's [`Record`]: its eleven sums and its approaching count.
pub const RECORD: usize = 12;

/// A particle's contact sums `[c(3), f(3), n(3), gap, count, approaching]`: the position
/// corrections, the partners' displacements this substep and the unit contact normals (each
/// summed), the signed gaps `dist - min_dist` summed, the number of contacts and, for the
/// movement-speed response, the number of approaching ones (the corrections `c` are then
/// averaged over those: [`corrections`]).
pub type Record = [f32; RECORD];

/// The corrections `c` of a record, rescaled from the contact count to the approaching count
/// when it has approaching contacts (the movement-speed response averages over those only).
#[inline(always)]
pub fn corrections(rec: &Record) -> [f32; 3] {
    let c = [rec[0], rec[1], rec[2]];
    if rec[11] > 0.0 {
        let scale = rec[10] / rec[11];
        c.map(|v| v * scale)
    } else {
        c
    }
}

/// The sums `[c(3), f(3), n(3), gap, count]` of a record as the correction reads them, the
/// corrections over the approaching contacts ([`corrections`]): the tests' view of a record.
#[cfg(test)]
pub(crate) fn finished(rec: &Record) -> [f32; 11] {
    let c = corrections(rec);
    std::array::from_fn(|k| if k < 3 { c[k] } else { rec[k] })
}

/// The twelve values of eight records as twelve lane vectors (value `c` of record `l` in
/// lane `l` of vector `c`): two 8 x 8 transposes, of values 0..8 and 4..12. Each value moves
/// as it is, so the lanes hold the records' bits.
#[inline(always)]
pub(crate) fn transpose_records(recs: &[Record; LANES]) -> [F32s; RECORD] {
    let half = |from: usize| {
        let rows: [F32s; LANES] = std::array::from_fn(|l| {
            let a: [f32; LANES] = recs[l][from..from + LANES].try_into().expect("eight values");
            F32s::from(a)
        });
        F32s::transpose(rows)
    };
    let (lo, hi) = (half(0), half(4));
    std::array::from_fn(|c| if c < LANES { lo[c] } else { hi[c - 4] })
}

/// The particles' sums while the pass adds its contacts in list order (see
/// `ContactPass::pair_pass`).
pub(crate) struct Accumulator<'a> {
    acc: &'a mut [Record],
    hit: &'a mut [bool],
    /// Contacts added.
    contacts: usize,
}

impl<'a> Accumulator<'a> {
    /// Starts a pass over the records `acc` (zero: the last correction zeroed those it read)
    /// and block flags `hit`, `old` the blocks the last pass touched.
    pub(crate) fn begin(acc: &'a mut [Record], hit: &'a mut [bool], old: &[u32]) -> Self {
        for &b in old {
            if let Some(h) = hit.get_mut(b as usize) {
                *h = false;
            }
        }
        Accumulator { acc, hit, contacts: 0 }
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

    /// Lists the blocks this pass touched in `touched` (ascending); returns the contacts
    /// added. Their records hold the sums until the correction reads and zeroes them.
    pub(crate) fn finish(self, touched: &mut Vec<u32>) -> usize {
        touched.clear();
        touched.extend(self.hit.iter().enumerate().filter(|(_, h)| **h).map(|(b, _)| b as u32));
        self.contacts
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        /// The lanes of eight transposed records hold each record's values bit for bit (signed
        /// zeros, NaN payloads, subnormals and infinities included, at random places).
        #[test]
        fn transposed_records_hold_each_records_bits(seed in proptest::prelude::any::<u64>(), every in 2usize..20) {
            let mut r = crate::test_rng::signed(seed);
            let specials = [-0.0f32, f32::from_bits(0x7fc0_1234), f32::from_bits(1), f32::INFINITY];
            let recs: [Record; LANES] =
                std::array::from_fn(|l| std::array::from_fn(|c| if (l + c) % every == 0 { specials[(l + c) % 4] } else { r() }));
            let lanes = transpose_records(&recs);
            for (c, v) in lanes.iter().enumerate() {
                for (l, got) in v.to_array().iter().enumerate() {
                    proptest::prop_assert_eq!(got.to_bits(), recs[l][c].to_bits(), "value {} of record {}", c, l);
                }
            }
        }
    }

    /// The corrections are rescaled to the approaching count only when there is one.
    #[test]
    fn corrections_average_over_the_approaching_contacts() {
        let mut rec: Record = [0.0; RECORD];
        rec[..3].copy_from_slice(&[0.3, -0.6, 0.9]);
        rec[10] = 3.0;
        assert_eq!(corrections(&rec), [0.3, -0.6, 0.9]);
        rec[11] = 1.0;
        assert_eq!(corrections(&rec), [0.3 * 3.0, -0.6 * 3.0, 0.9 * 3.0]);
    }
}
