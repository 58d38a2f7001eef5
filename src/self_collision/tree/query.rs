//! The tree's query: for each particle, a depth-first walk to the leaves whose boxes meet its
//! search box, and the lane scan of their particles (the method is in [`super`]).

use crate::data::exec::Exec;
use crate::self_collision::neighbours::{check_max_dist, retain_tail, search_radius, sort_dedup_tail, Candidates, Neighbours};
use crate::self_collision::tree::{ParticleTree, MAX_DEPTH};
use crate::Result;
use rayon::prelude::*;

impl ParticleTree {
    /// For every particle, its neighbours within `max_dist`, sorted, into `out`; parallel over
    /// particles. The positions must be those of the last refit (checked bitwise in one pass:
    /// leaf scans read the leaf-ordered copy the refit made). Errors if they are not, if `n`
    /// differs from the build, an array is short, or `max_dist` is negative or non-finite.
    pub fn query_all(&self, x: &[f32], y: &[f32], z: &[f32], n: usize, max_dist: f32, out: &mut Neighbours) -> Result<()> {
        self.query_exec(x, y, z, n, max_dist, out, Exec::Parallel, false, &|_, _| true)
    }

    /// Serial, scalar twin of [`ParticleTree::query_all`] (no threads, no lanes); produces
    /// identical lists.
    pub fn query_all_serial(&self, x: &[f32], y: &[f32], z: &[f32], n: usize, max_dist: f32, out: &mut Neighbours) -> Result<()> {
        self.query_exec(x, y, z, n, max_dist, out, Exec::Scalar, false, &|_, _| true)
    }

    /// [`ParticleTree::query_all`] when `exec` is parallel, else a serial walk with the lanes of
    /// `exec` (never entering rayon); identical lists. With `upper`, each pair is listed once,
    /// in the list of its smaller id (half the candidates, the same pairs). Only the pairs with
    /// `keep(i, j)` are listed, filtered particle by particle (so the lists' limit counts the
    /// kept pairs only).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn query_exec<K>(
        &self,
        x: &[f32],
        y: &[f32],
        z: &[f32],
        n: usize,
        max_dist: f32,
        out: &mut Neighbours,
        exec: Exec,
        upper: bool,
        keep: &K,
    ) -> Result<()>
    where
        K: Fn(usize, u32) -> bool + Sync,
    {
        self.check_n(x, y, z, n)?;
        let md2 = check_max_dist(max_dist)?;
        let r = search_radius(max_dist);
        // The parallel query scans with lanes whatever `exec.simd()` says: the lists are the same.
        let (parallel, lanes) = (exec.parallel(), exec.parallel() || exec.simd());
        let scan = |i: usize, buf: &mut Vec<u32>| {
            let start = buf.len();
            if lanes {
                self.scan::<true>(x, y, z, i, md2, r, upper, buf)
            } else {
                self.scan::<false>(x, y, z, i, md2, r, upper, buf)
            }
            retain_tail(buf, start, |j| keep(i, j));
        };
        if parallel {
            Self::check_unchanged((0..n).into_par_iter().all(|i| self.unchanged(x, y, z, i)))?;
            out.fill_parallel(n, scan)
        } else {
            Self::check_unchanged((0..n).all(|i| self.unchanged(x, y, z, i)))?;
            out.fill_serial(n, scan)
        }
    }

    /// Appends the sorted neighbours of particle `i` to `buf` (those above `i` with `above`).
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn scan<const SIMD: bool>(&self, x: &[f32], y: &[f32], z: &[f32], i: usize, md2: f32, r: f32, above: bool, buf: &mut Vec<u32>) {
        let (xi, yi, zi) = (x[i], y[i], z[i]);
        if !(xi.is_finite() && yi.is_finite() && zi.is_finite()) {
            return;
        }
        let (qlo, qhi) = ([xi - r, yi - r, zi - r], [xi + r, yi + r, zi + r]);
        let fl = self.first_leaf();
        let start = buf.len();
        let iu = i as u32;
        // Depth-first: the stack never holds more than depth + 1 <= 21 nodes.
        let mut stack = [0u32; 2 * MAX_DEPTH as usize + 2];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let k = stack[sp] as usize;
            let b = &self.boxes[k];
            if b.min[0] > qhi[0] || b.max[0] < qlo[0] || b.min[1] > qhi[1] || b.max[1] < qlo[1] || b.min[2] > qhi[2] || b.max[2] < qlo[2] {
                continue;
            }
            if k >= fl {
                let l = k - fl;
                let range = self.leaf_start[l] as usize..self.leaf_start[l + 1] as usize;
                let c = Candidates {
                    above,
                    ids: &self.order,
                    x: &self.lx,
                    y: &self.ly,
                    z: &self.lz,
                };
                c.scan::<SIMD>(range, iu, [xi, yi, zi], md2, buf);
            } else {
                stack[sp] = (2 * k + 2) as u32;
                stack[sp + 1] = (2 * k + 1) as u32;
                sp += 2;
            }
        }
        sort_dedup_tail(buf, start);
    }
}
