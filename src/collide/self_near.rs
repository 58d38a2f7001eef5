//! The near list: the candidate pairs the substeps test, kept across substeps (exact, like the
//! candidate lists of [`super::self_verlet`]; the method is described in
//! [`super::self_collision`]).
//!
//! A contact needs `|p_i - p_j| < d` for the predicted positions `p`. The near list holds the
//! candidate pairs within `d + s₂` of the positions `y` of its build (a substep's `p`); while
//! every particle of the active blocks stays within `0.49 s₂` of `y`, a pair in contact is in
//! it. The substeps test only the near pairs, and a pair also has to be within `q` at the
//! step's start (in the lists of the step), exactly as the fresh path requires.

use super::neighbours::Neighbours;
use super::self_verlet::{max_disp2, SAFE};

/// Near pairs of the candidate lists for the substeps (see the module docs).
#[derive(Clone, Debug, Default)]
pub(crate) struct NearList {
    /// Pairs `(i, j)`, `i < j`, ordered by `i` then `j`.
    pub(crate) pairs: Vec<(u32, u32)>,
    /// Positions of the build (particle arrays, padded like them).
    at: [Vec<f32>; 3],
    skin: f32,
    valid: bool,
    subs_since: u32,
    /// Builds so far.
    pub(crate) rebuilds: u64,
}

impl NearList {
    /// Forgets the list (new candidate lists).
    pub(crate) fn invalidate(&mut self) {
        self.valid = false;
    }

    /// Makes the list hold for the predicted positions `p` (`len` entries checked: the
    /// particles of the active blocks are among them): kept if no particle moved more than
    /// `0.49 s₂` since the build, else rebuilt from `cand` with a new skin.
    pub(crate) fn update(&mut self, cand: &Neighbours, p: [&[f32]; 3], len: usize, n: usize, d: f32, simd: bool) {
        let len = len.min(p[0].len());
        if self.valid && self.at[0].len() >= len {
            let at = [&self.at[0][..], &self.at[1][..], &self.at[2][..]];
            let m2 = max_disp2(p, at, len, simd);
            let lim = 0.5 * SAFE * self.skin;
            self.subs_since += 1;
            if m2 <= lim * lim {
                return;
            }
            // Aim at about 20 substeps between builds, within [d / 8, d].
            let rate = if m2.is_finite() { m2.sqrt() / self.subs_since as f32 } else { d };
            self.skin = (20.0 * rate).clamp(0.125 * d, d);
        } else if !self.valid {
            self.skin = 0.25 * d;
        }
        for (a, src) in self.at.iter_mut().zip(p) {
            a.clear();
            a.extend_from_slice(&src[..len]);
        }
        let r = d + self.skin;
        let r2 = r * r;
        self.pairs.clear();
        for i in 0..n.min(cand.len()) {
            let pi = [p[0][i], p[1][i], p[2][i]];
            for &j in cand.of(i) {
                let j = j as usize;
                let v = [pi[0] - p[0][j], pi[1] - p[1][j], pi[2] - p[2][j]];
                let d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
                // NaN passes: the exact test rejects it later, as the fresh path does.
                if d2 < r2 || d2.is_nan() {
                    self.pairs.push((i as u32, j as u32));
                }
            }
        }
        self.valid = true;
        self.subs_since = 0;
        self.rebuilds += 1;
    }
}
