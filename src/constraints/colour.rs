//! Greedy graph colouring of constraints.
//!
//! Constraints are visited in order; each takes the smallest colour not yet used by any of its
//! particles. Per particle a 64-bit mask records the colours used, so the pass is linear. A
//! grid cloth with stretch, shear and bend needs about a dozen colours. Beyond 64 colours
//! (pathological inputs, e.g. one particle in many constraints) further constraints spill into
//! extra colours found by a slower scan, so colouring never fails.

use crate::constraints::distance::{Colour, DistanceInput, FAMILY_MIN};

/// Assigns a colour to each pair `(a, b)`; returns the colour per pair and the colour count.
pub fn colour_pairs(pairs: &[(u32, u32)], particle_count: usize) -> (Vec<u32>, u32) {
    let mut used = vec![0u64; particle_count];
    let mut colours = Vec::with_capacity(pairs.len());
    let mut overflow: Vec<usize> = Vec::new();
    let mut count = 0u32;
    for (k, &(a, b)) in pairs.iter().enumerate() {
        let m = used[a as usize] | used[b as usize];
        let c = (!m).trailing_zeros();
        if c >= 64 {
            colours.push(u32::MAX);
            overflow.push(k);
            continue;
        }
        used[a as usize] |= 1 << c;
        used[b as usize] |= 1 << c;
        colours.push(c);
        count = count.max(c + 1);
    }
    if !overflow.is_empty() {
        // Rare: colour the rest with explicit per-colour particle sets.
        let mut next = count.max(64);
        let mut sets: Vec<std::collections::HashSet<u32>> = Vec::new();
        for k in overflow {
            let (a, b) = pairs[k];
            let slot = sets.iter().position(|s| !s.contains(&a) && !s.contains(&b));
            let slot = match slot {
                Some(s) => s,
                None => {
                    sets.push(Default::default());
                    sets.len() - 1
                }
            };
            sets[slot].insert(a);
            sets[slot].insert(b);
            colours[k] = 64 + slot as u32;
            next = next.max(64 + slot as u32 + 1);
        }
        count = next;
    }
    (colours, count)
}

/// The general colouring of constraints that are not whole grid classes, laid out by colour
/// (the caller pads and plans them).
pub(crate) fn colour_families(input: &[DistanceInput], particle_count: usize) -> Vec<Colour> {
    // Large offset families (same `b − a`: on a grid, horizontal stretch, vertical bend, a
    // shear diagonal...) are coloured greedily family after family, each in order of `a`,
    // which gives mostly regular colours (alternate edges, alternate rows). The rest
    // (irregular meshes, short pieces, any world below `FAMILY_MIN` per family) is coloured
    // on its own in input order, as it always was, so small worlds keep their Gauss–Seidel
    // order. Each colour is then laid out by offset and `a` (free within a colour), which
    // the block plans turn into contiguous loads and stores.
    let offset = |k: usize| input[k].b as i64 - input[k].a as i64;
    let mut order: Vec<usize> = (0..input.len()).collect();
    order.sort_by_key(|&k| (offset(k), input[k].a));
    let (mut large, mut rest) = (Vec::new(), Vec::new());
    for family in order.chunk_by(|&i, &j| offset(i) == offset(j)) {
        if family.len() >= FAMILY_MIN {
            large.extend_from_slice(family);
        } else {
            rest.extend_from_slice(family);
        }
    }
    rest.sort_unstable();
    let groups = [large, rest];
    let (mut colour_of, mut count) = (vec![0u32; input.len()], 0u32);
    for g in &groups {
        let pairs: Vec<(u32, u32)> = g.iter().map(|&k| (input[k].a, input[k].b)).collect();
        let (c, n) = colour_pairs(&pairs, particle_count);
        for (&k, c) in g.iter().zip(c) {
            colour_of[k] = c + count;
        }
        count += n;
    }
    // Stable: within a colour, the (offset, a) order from above.
    order.sort_by_key(|&k| colour_of[k]);
    let colour_of: Vec<u32> = order.iter().map(|&k| colour_of[k]).collect();
    let mut colours = vec![Colour::default(); count as usize];
    for (&k, &col) in order.iter().zip(&colour_of) {
        let (c, col) = (&input[k], &mut colours[col as usize]);
        col.a.push(c.a);
        col.b.push(c.b);
        col.rest.push(c.rest);
        col.compliance.push(c.compliance);
    }
    colours
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(pairs: &[(u32, u32)], n: usize) {
        let (c, count) = colour_pairs(pairs, n);
        for col in 0..count {
            let mut seen = std::collections::HashSet::new();
            for (k, &(a, b)) in pairs.iter().enumerate() {
                if c[k] == col {
                    assert!(seen.insert(a) && (a == b || seen.insert(b)), "colour {col} shares a particle");
                }
            }
        }
        assert!(c.iter().all(|&x| x < count));
    }

    #[test]
    fn chain_needs_two_colours() {
        let pairs: Vec<_> = (0..10).map(|i| (i, i + 1)).collect();
        let (_, count) = colour_pairs(&pairs, 11);
        assert_eq!(count, 2);
        check(&pairs, 11);
    }

    #[test]
    fn star_overflows_64_and_stays_valid() {
        let pairs: Vec<_> = (1..200).map(|i| (0, i)).collect();
        let (_, count) = colour_pairs(&pairs, 200);
        assert_eq!(count, 199);
        check(&pairs, 200);
    }
}
