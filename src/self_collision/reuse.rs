//! Candidate lists kept across steps (Verlet lists with a skin).
//!
//! The broadphase may run with the reach `q + s`, `s` the skin, and its candidates be kept
//! while no particle has moved more than `s / 2` (less a rounding margin) since: two particles
//! then closed in by less than `s`, so every pair within `q` now was within `q + s` at the
//! build. Each step's lists are the candidates within `q` of each other at the step's start
//! (the broadphase's own predicate), exactly the lists of a fresh query: the reuse changes the
//! cost, never the result.
//!
//! The skin pays only when the lists then last several steps: a wider reach finds more
//! candidates, and a cloth that moves its skin in a step or two rebuilds anyway. So the skin
//! is `SKIN_FACTOR d` when the particles moved at most a quarter of that a step over the last
//! lists' life, else zero (no candidates kept, the query's lists used as they are).

use crate::data::exec::Exec;
use crate::error::Result;
use crate::model::self_collision::SelfBroadphase;
use crate::self_collision::neighbours::{within, Neighbours};

/// The skin in collision distances when the particles move slowly.
const SKIN_FACTOR: f32 = 1.0;

/// The candidates' build and how fast the particles moved since.
#[derive(Clone, Debug, Default)]
pub(crate) struct Reuse {
    /// Positions at the build.
    at: [Vec<f32>; 3],
    /// What the candidates were built for: particle count, distance (bits), broadphase.
    key: Option<(usize, u32, SelfBroadphase)>,
    skin: f32,
    /// Steps since the build.
    age: u32,
    /// Largest move a step over the last lists' life (the move since the build over their
    /// age), m.
    rate: f32,
    /// Builds of the candidate lists.
    pub(crate) builds: u64,
}

impl Reuse {
    /// Whether candidates built for distance `d` still hold every pair within `q` of the
    /// positions `x` (the first `n`); else forgets them.
    pub(crate) fn holds(&mut self, x: [&[f32]; 3], n: usize, d: f32, broadphase: SelfBroadphase) -> bool {
        self.age += 1;
        if self.key != Some((n, d.to_bits(), broadphase)) {
            self.key = None;
            return false;
        }
        let moved = max_move(x, [&self.at[0], &self.at[1], &self.at[2]], n);
        self.rate = moved / self.age as f32;
        // `moved` is NaN for a non-finite particle: rebuild (the broadphase reports it).
        let keep = moved < 0.49 * self.skin;
        if !keep {
            self.key = None;
        }
        keep
    }

    /// The skin of the next build for distance `d`.
    pub(crate) fn next_skin(&self, d: f32) -> f32 {
        let s = SKIN_FACTOR * d;
        if self.builds > 0 && self.rate <= 0.25 * s {
            s
        } else {
            0.0
        }
    }

    /// Records a build from `x` with `skin` for distance `d`.
    pub(crate) fn built(&mut self, x: [&[f32]; 3], n: usize, d: f32, broadphase: SelfBroadphase, skin: f32) {
        for (a, src) in self.at.iter_mut().zip(x) {
            a.clear();
            a.extend_from_slice(&src[..n.min(src.len())]);
        }
        self.key = Some((n, d.to_bits(), broadphase));
        self.skin = skin;
        self.age = 0;
        self.builds += 1;
    }

    /// The skin of the candidates in use.
    pub(crate) fn skin(&self) -> f32 {
        self.skin
    }
}

/// The largest distance a particle moved from `b` to `a` (NaN if any is non-finite).
fn max_move(a: [&[f32]; 3], b: [&[f32]; 3], n: usize) -> f32 {
    let mut m2 = 0.0f32;
    for i in 0..n {
        let (dx, dy, dz) = (a[0][i] - b[0][i], a[1][i] - b[1][i], a[2][i] - b[2][i]);
        let d2 = dx * dx + dy * dy + dz * dz;
        if d2.is_nan() {
            return f32::NAN;
        }
        m2 = m2.max(d2);
    }
    m2.sqrt()
}

/// The lists `out`: the candidates `cand` within `q` of each other at `x`, by the
/// broadphase's predicate (in parallel over fixed chunks when `exec` is; the same lists).
pub(crate) fn within_reach(cand: &Neighbours, x: [&[f32]; 3], q: f32, out: &mut Neighbours, exec: Exec) -> Result<()> {
    let q2 = q * q;
    let keep = |i: usize, buf: &mut Vec<u32>| {
        let (xi, yi, zi) = (x[0][i], x[1][i], x[2][i]);
        for &j in cand.of(i) {
            if within(xi, yi, zi, x[0][j as usize], x[1][j as usize], x[2][j as usize], q2) {
                buf.push(j);
            }
        }
    };
    if exec.parallel() {
        out.fill_parallel(cand.len(), keep)
    } else {
        out.fill_serial(cand.len(), keep)
    }
}
