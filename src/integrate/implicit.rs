//! Implicit (backward) Euler on the mass-spring model, Baraff & Witkin 1998 ("Large Steps in
//! Cloth Simulation", section 3), solved with a sparse Cholesky factorisation from `faer`.
//!
//! Backward Euler asks for `v_{n+1} = v_n + h M⁻¹ F(x_n + h v_{n+1})`. Linearising the spring
//! forces once about `x_n` (one Newton step, as Baraff and Witkin do) with `K = ∂F/∂x` gives the
//! linear system for `Δv = v_{n+1} - v_n`:
//!
//! ```text
//! (M - h² K) Δv = h (F(x_n) + h K v_n),     x_{n+1} = x_n + h v_{n+1}
//! ```
//!
//! For a spring `(a, b)` with `d = x_b - x_a`, `l = |d|`, `n = d / l`, rest length `L`:
//! `∂f_a/∂x_a = -k [n nᵀ + max(0, 1 - L/l) (I - n nᵀ)]` (the other blocks follow by sign). The
//! transverse term is clamped at zero for compressed springs (Choi & Ko 2002), which keeps
//! `-K` positive semi-definite, so `A = M - h² K` is symmetric positive definite for any `h`:
//! the method is unconditionally stable, at the price of numerical damping (first order).
//! Drag and fabric damping are applied after the solve with the same factors as the other
//! methods; gravity and wind enter `F` and have no Jacobian.
//!
//! Pinned particles (`w = 0`) are not unknowns: their rows and columns are dropped, so they keep
//! their velocity (zero) and the couplings to them remain only on the free side's diagonal.
//!
//! **Why sparse Cholesky, not preconditioned CG.** `A` is SPD with a sparsity pattern that only
//! changes with the topology or the set of pinned particles, so faer's symbolic analysis
//! (fill-reducing ordering, elimination tree, supernodes) is done once and only the numeric
//! factorisation runs per substep, into buffers kept with the layout (no allocation per
//! substep). A direct solve is exact to rounding, so the measured error is
//! the integrator's and not a tolerance's; it is deterministic (faer is built without its rayon
//! feature, hence sequential; duplicate entries are summed in assembly order and the rest of the
//! summation order is fixed by the symbolic structure), so
//! results do not depend on the thread count; and for the stiff cloth this method exists for,
//! `h² k / m` is large, `A` is badly conditioned and CG would need many iterations. For a cloth
//! grid of `n` particles the factor stays near-linear in size under the ordering, which is
//! cheap up to the sizes the accuracy reports use. The assembly is scalar and in f64.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, SymbolicCholesky};
use faer::sparse::{Pair, SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, Par, Side};

use crate::constraints::DistanceSet;
use crate::data::particles::Particles;
use crate::error::{Result, WeftError};
use crate::integrate::springs::spring_stiffness;

/// Marks a particle that is not an unknown (pinned).
const NOT_FREE: u32 = u32::MAX;

/// The implicit solver's layout and symbolic factorisation, rebuilt when the topology, the set
/// of pinned particles or the stiffness changes.
pub struct ImplicitState {
    layout: Layout,
    /// Pattern, symbolic factorisation and numeric buffers (`None` when nothing is free).
    solver: Option<Solver>,
}

/// The sparse Cholesky solver of one layout, with every buffer a substep needs, so a substep
/// allocates nothing: the matrix values in pattern order, the factor's values and the
/// workspace of the numeric factorisation and the solve (sequential).
struct Solver {
    pattern: SymbolicSparseColMat<usize>,
    /// Where each assembled entry (in [`Layout::assemble`]'s order) adds into `values`.
    slot: Vec<usize>,
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    factor: Vec<f64>,
    stack: MemBuffer,
}

impl Solver {
    fn new(n_dof: usize, idx: &[Pair<usize, usize>]) -> Result<Solver> {
        let (pattern, _) = SymbolicSparseColMat::try_new_from_indices(n_dof, n_dof, idx).map_err(faer_err)?;
        // The pattern's rows are sorted within each column: find each entry's place once.
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let slot = idx
            .iter()
            .map(|e| {
                let rows = &row_idx[col_ptr[e.col]..col_ptr[e.col + 1]];
                rows.binary_search(&e.row)
                    .map(|k| col_ptr[e.col] + k)
                    .map_err(|_| faer_err("entry not in its pattern"))
            })
            .collect::<Result<Vec<usize>>>()?;
        let symbolic =
            factorize_symbolic_cholesky(pattern.as_ref(), Side::Lower, Default::default(), Default::default()).map_err(faer_err)?;
        let scratch = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        Ok(Solver {
            values: vec![0.0; row_idx.len()],
            factor: vec![0.0; symbolic.len_val()],
            stack: MemBuffer::try_new(scratch).map_err(faer_err)?,
            pattern,
            slot,
            symbolic,
        })
    }

    /// Solves `A x = rhs` in place for the assembled entries `vals` of `A`'s lower triangle
    /// (duplicates summed in assembly order).
    fn solve(&mut self, vals: &[f64], rhs: &mut [f64]) -> Result<()> {
        self.values.fill(0.0);
        for (&k, &v) in self.slot.iter().zip(vals) {
            self.values[k] += v;
        }
        let a = SparseColMatRef::new(self.pattern.as_ref(), &self.values);
        let llt = self
            .symbolic
            .factorize_numeric_llt::<f64>(
                &mut self.factor,
                a,
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut self.stack),
                Default::default(),
            )
            .map_err(|_| WeftError::Diverged {
                particle: 0,
                stage: "implicit-euler (matrix not positive definite)",
            })?;
        let n = rhs.len();
        llt.solve_in_place_with_conj(
            Conj::No,
            faer::MatMut::from_column_major_slice_mut(rhs, n, 1),
            Par::Seq,
            MemStack::new(&mut self.stack),
        );
        Ok(())
    }
}

/// Unknowns, springs and the assembly buffers.
struct Layout {
    /// Block index of each particle, or `NOT_FREE`.
    free: Vec<u32>,
    /// Springs: `a, b, rest, k`.
    springs: Vec<(usize, usize, f64, f64)>,
    stiffness: f32,
    n_dof: usize,
    vals: Vec<f64>,
    rhs: Vec<f64>,
}

/// `k [n nᵀ + c (I - n nᵀ)]` of one spring at positions `xa, xb`, and its force on `a`.
fn spring_block(xa: [f64; 3], xb: [f64; 3], rest: f64, k: f64) -> ([[f64; 3]; 3], [f64; 3]) {
    let d = [xb[0] - xa[0], xb[1] - xa[1], xb[2] - xa[2]];
    let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if l <= crate::constraints::distance::MIN_LENGTH as f64 {
        return ([[0.0; 3]; 3], [0.0; 3]);
    }
    let n = d.map(|c| c / l);
    let c = (1.0 - rest / l).max(0.0);
    let mut m = [[0.0; 3]; 3];
    for (r, row) in m.iter_mut().enumerate() {
        for (s, e) in row.iter_mut().enumerate() {
            let nn = n[r] * n[s];
            *e = k * (nn + c * (if r == s { 1.0 } else { 0.0 } - nn));
        }
    }
    (m, n.map(|e| k * (l - rest) * e))
}

impl ImplicitState {
    fn new(p: &Particles, distance: &DistanceSet, stiffness: f32) -> Result<ImplicitState> {
        let n = p.count();
        let mut free = vec![NOT_FREE; n];
        let mut n_free = 0u32;
        for (i, f) in free.iter_mut().enumerate() {
            if p.w[i] > 0.0 {
                *f = n_free;
                n_free += 1;
            }
        }
        let springs = distance
            .colours
            .iter()
            .flat_map(|c| {
                (0..c.real).map(move |k| {
                    let ks = spring_stiffness(c.compliance[k], stiffness) as f64;
                    (c.a[k] as usize, c.b[k] as usize, c.rest[k] as f64, ks)
                })
            })
            .collect();
        let mut layout = Layout {
            free,
            springs,
            stiffness,
            n_dof: 3 * n_free as usize,
            vals: Vec::new(),
            rhs: Vec::new(),
        };
        let mut idx = Vec::new();
        layout.assemble(p, 0.0, |r, c| idx.push(Pair { row: r, col: c }));
        let solver = if layout.n_dof > 0 {
            Some(Solver::new(layout.n_dof, &idx)?)
        } else {
            None
        };
        Ok(ImplicitState { layout, solver })
    }

    /// Whether this layout still fits the particles, constraints and stiffness.
    fn fits(&self, p: &Particles, distance: &DistanceSet, stiffness: f32) -> bool {
        let l = &self.layout;
        l.stiffness == stiffness
            && l.free.len() == p.count()
            && l.springs.len() == distance.len()
            && l.free.iter().zip(&p.w).all(|(&f, &w)| (f != NOT_FREE) == (w > 0.0))
    }
}

impl Layout {
    /// Fills `vals` (lower triangle of `M - h² K`, in a fixed order that depends only on the
    /// layout) and `rhs` (`h (F + h K v)` without external forces), calling `index` with each
    /// entry's row and column in that same order.
    fn assemble(&mut self, p: &Particles, h: f64, mut index: impl FnMut(usize, usize)) {
        self.vals.clear();
        self.rhs.clear();
        self.rhs.resize(self.n_dof, 0.0);
        let pos = |i: usize| p.position(i).map(f64::from);
        let vel = |i: usize| p.velocity(i).map(f64::from);
        for (i, &b) in self.free.iter().enumerate() {
            if b != NOT_FREE {
                let m = 1.0 / p.w[i] as f64;
                for r in 0..3 {
                    for c in 0..=r {
                        index(3 * b as usize + r, 3 * b as usize + c);
                        self.vals.push(if r == c { m } else { 0.0 });
                    }
                }
            }
        }
        let h2 = h * h;
        for &(a, b, rest, k) in &self.springs {
            let (ks, fa) = spring_block(pos(a), pos(b), rest, k);
            let (va, vb) = (vel(a), vel(b));
            let dv = [va[0] - vb[0], va[1] - vb[1], va[2] - vb[2]];
            // (K v)_a = -Ks (v_a - v_b), (K v)_b = +Ks (v_a - v_b); F_b = -F_a.
            let kdv: [f64; 3] = std::array::from_fn(|r| ks[r][0] * dv[0] + ks[r][1] * dv[1] + ks[r][2] * dv[2]);
            for (node, sign) in [(a, 1.0), (b, -1.0)] {
                let blk = self.free[node];
                if blk == NOT_FREE {
                    continue;
                }
                let o = 3 * blk as usize;
                for (r, row) in ks.iter().enumerate() {
                    self.rhs[o + r] += h * sign * (fa[r] - h * kdv[r]);
                    for (c, &e) in row.iter().enumerate().take(r + 1) {
                        index(o + r, o + c);
                        self.vals.push(h2 * e);
                    }
                }
            }
            let (ba, bb) = (self.free[a], self.free[b]);
            if ba != NOT_FREE && bb != NOT_FREE {
                let (hi, lo) = (3 * ba.max(bb) as usize, 3 * ba.min(bb) as usize);
                for (r, row) in ks.iter().enumerate() {
                    for (c, &e) in row.iter().enumerate() {
                        index(hi + r, lo + c);
                        self.vals.push(-h2 * e);
                    }
                }
            }
        }
    }
}

fn faer_err(e: impl std::fmt::Debug) -> WeftError {
    WeftError::param("solver.method", "implicit-euler", format!("sparse solver failed: {e:?}"))
}

/// What one implicit substep reads besides the particles and constraints.
pub(crate) struct ImplicitSubstep<'a> {
    /// Substep length, s.
    pub h: f32,
    /// Spring stiffness of zero-compliance constraints, N/m.
    pub stiffness: f32,
    /// Gravity, m/s², if named.
    pub gravity: Option<[f32; 3]>,
    /// Wind force per particle, N, if named (computed at the substep's start).
    pub wind: Option<[&'a [f32]; 3]>,
    /// Drag coefficient, if named.
    pub drag: Option<f32>,
    /// Per-particle damping factor for this `h`, if any fabric damps.
    pub damp: Option<&'a [f32]>,
    /// Write only the prediction `p` (the collision stages follow and then set `x`).
    pub keep_x: bool,
}

impl ImplicitState {
    /// One implicit Euler substep: `state` is reused when it still fits, rebuilt otherwise.
    pub(crate) fn substep(
        slot: &mut Option<ImplicitState>,
        p: &mut Particles,
        distance: &DistanceSet,
        sub: &ImplicitSubstep<'_>,
    ) -> Result<()> {
        let mut state = match slot.take() {
            Some(st) if st.fits(p, distance, sub.stiffness) => st,
            _ => ImplicitState::new(p, distance, sub.stiffness)?,
        };
        let h = sub.h;
        let hd = h as f64;
        let st = &mut state.layout;
        st.assemble(p, hd, |_, _| {});
        let g = sub.gravity.map(|g| g.map(f64::from));
        if g.is_some() {
            crate::model::effects::probe::enter(crate::model::effects::probe::GRAVITY);
        }
        for (i, &b) in st.free.iter().enumerate() {
            if b == NOT_FREE {
                continue;
            }
            let m = 1.0 / p.w[i] as f64;
            let o = 3 * b as usize;
            for k in 0..3 {
                let mut f = g.map_or(0.0, |g| m * g[k]);
                if let Some(w) = &sub.wind {
                    f += w[k][i] as f64;
                }
                st.rhs[o + k] += hd * f;
            }
        }
        if let Some(solver) = &mut state.solver {
            solver.solve(&st.vals, &mut st.rhs)?;
        }
        let n = p.count();
        let drag = sub.drag.map(|c| c * h);
        if drag.is_some() {
            crate::model::effects::probe::enter(crate::model::effects::probe::DRAG);
        }
        for i in 0..n {
            let mut v = [p.vx[i], p.vy[i], p.vz[i]];
            let b = st.free[i];
            if b != NOT_FREE {
                for (k, vk) in v.iter_mut().enumerate() {
                    *vk = (*vk as f64 + st.rhs[3 * b as usize + k]) as f32;
                }
            }
            if let Some(hc) = drag {
                let s = 1.0 / (1.0 + hc * p.w[i]);
                v = v.map(|e| e * s);
            }
            if let Some(d) = sub.damp {
                v = v.map(|e| e * d[i]);
            }
            (p.vx[i], p.vy[i], p.vz[i]) = (v[0], v[1], v[2]);
            let x = [p.x[i] + v[0] * h, p.y[i] + v[1] * h, p.z[i] + v[2] * h];
            if !sub.keep_x {
                (p.x[i], p.y[i], p.z[i]) = (x[0], x[1], x[2]);
            }
            (p.px[i], p.py[i], p.pz[i]) = (x[0], x[1], x[2]);
        }
        *slot = Some(state);
        Ok(())
    }
}

#[cfg(test)]
#[path = "implicit_tests.rs"]
mod tests;
