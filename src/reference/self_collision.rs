//! Cloth self-collision in f64 for the reference step: particle–particle contacts with the
//! world's rules (Shapri, Sulaiman & Bade 2016 and Müller's "Ten Minute Physics"; the world's version is
//! `src/self_collision/`: `mod.rs`, `pairs.rs`, `response.rs`), read naively.
//!
//! With `d` the collision distance and `r_i` the rest (initial grid) position of particle `i`:
//!
//! * **Once per step**, from the positions `x` and velocities `v` at its start: each
//!   particle's travel `t_i = min(travel, max(0.25, 1.5 u_i dt / d))`, `u_i` the larger of
//!   `|v_i - m|` and `|m|`, `m` the mean velocity of the free particles; then every pair
//!   closer than its reach `d + (t_i + t_j) d` (a plain uniform grid of cell `(1 + 2 max t) d`
//!   in f64 and a 27-cell search), each pair once, leaving out **rest neighbours** (one cloth
//!   and `|r_i - r_j| <= 1.001 (1 + 2 travel) d`, the setting's travel: the cloth's own
//!   constraints hold them).
//! * **After predict** (each substep), the speed clamp: `u = v_i - m` is limited to
//!   `|u| <= t_i d / (substeps h)` (a relative travel of `t_i d` per step), and a clamped
//!   particle's prediction is redone, `p = x + h v`. The clamped predictions `q` are the
//!   VcCPBD box centres.
//! * **After the constraint sweeps** (each substep), for every listed pair, for each end `i`
//!   that is free, using the predictions `p` of all particles (Jacobi):
//!
//! ```text
//! same cloth and |p_i - p_j| > |r_i - r_j|: no contact (Müller's rest rule)
//! min_dist = min(d, |r_i - r_j|) (d for two cloths);  contact if |p_i - p_j| < min_dist
//! n = (p_i - p_j)/|p_i - p_j|, else the rest direction, else ±(1,2,3)/√14 by id order
//! PBD, VcCPBD: c_i += w_i/(w_i + w_j) (min_dist - dist) n
//! movement speed: v_n = ((p_i - x_i) - (p_j - x_j)).n; if v_n < 0: c_i -= w_i/(w_i + w_j) v_n n
//! sums: f_i += p_j - x_j, n_i += n, g_i += dist - min_dist, k_i += 1
//! ```
//!
//!   then, for a free particle with `k > 0` (movement speed divides `c` by its approaching
//!   contacts instead): `t = p + c/k + μ (f/k - (p - x))/2`; VcCPBD also: if `|t - q| >= d`,
//!   `p = q`, else with `β = min(b h, 1)` (`b` the particle's damping rate) and `n̂ = n/|n|`,
//!   `p = t - (β (t - x).n̂ + β² g/(4k)) n̂`; PBD and movement speed: `p = t`.

use crate::model::description::WorldDescription;
use crate::model::self_collision::Response;
use crate::model::self_collision::{BOX_RADIUS, RELAXATION, TRAVEL_FLOOR, TRAVEL_GROWTH};
use std::collections::HashMap;

type V3 = [f64; 3];

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The unit direction for coincident particles with no rest direction.
const COINCIDENT: V3 = [0.267_261_241_912_424_4, 0.534_522_483_824_848_8, 0.801_783_725_737_273_2];

/// Self-collision state of the reference.
#[derive(Clone, Debug)]
pub(super) struct SelfCollision64 {
    d: f64,
    response: Response,
    friction: f64,
    /// The travel bound `T / d` and the rest-skip radius over `d` (the world's settings, read
    /// as the world reads them), and each particle's travel over `d` this step.
    travel: f64,
    skip: f64,
    step_travel: Vec<f64>,
    /// Rest positions and cloth of every particle.
    rest: Vec<V3>,
    cloth_of: Vec<usize>,
    /// Partners `j > i` of each particle `i` for the current step.
    pub(super) lists: Vec<Vec<usize>>,
    /// The clamped predictions (box centres) of the current substep.
    q: Vec<V3>,
}

/// The mean velocity of the free particles (`w > 0`), zero when there are none.
fn mean_free(v: &[V3], w: &[f64]) -> V3 {
    let (mut m, mut free) = ([0.0; 3], 0.0);
    for (vi, _) in v.iter().zip(w).filter(|(_, &wi)| wi > 0.0) {
        for k in 0..3 {
            m[k] += vi[k];
        }
        free += 1.0;
    }
    if free > 0.0 {
        m = m.map(|c| c / free);
    }
    m
}

/// Contact sums of one particle.
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    c: V3,
    f: V3,
    n: V3,
    gap: f64,
    count: f64,
    approaching: f64,
}

impl SelfCollision64 {
    /// The f64 copy of `world`'s self-collision, `None` when it is off. Rest positions are the
    /// world's positions now (copy a world before its first step). `Err` names what it cannot
    /// represent: particles that belong to no cloth.
    pub(super) fn from_desc(desc: &WorldDescription) -> Result<Option<Self>, &'static str> {
        let Some(cfg) = &desc.self_collision else { return Ok(None) };
        let d = desc.self_collision_distance as f64;
        if !(d > 0.0 && d.is_finite()) {
            return Ok(None);
        }
        let n = desc.positions.len();
        let mut cloth_of = vec![usize::MAX; n];
        for (k, c) in desc.cloths.iter().enumerate() {
            let first = c.first as usize;
            for slot in cloth_of.iter_mut().skip(first).take((c.rows * c.cols) as usize) {
                *slot = k;
            }
        }
        if cloth_of.contains(&usize::MAX) {
            return Err("self-collision with particles outside cloths (strands)");
        }
        Ok(Some(SelfCollision64 {
            d,
            response: cfg.response,
            friction: cfg.friction as f64,
            travel: cfg.travel as f64,
            skip: cfg.rest_skip_factor() as f64,
            step_travel: vec![cfg.travel as f64; n],
            rest: desc.positions.iter().map(|p| p.map(f64::from)).collect(),
            cloth_of,
            lists: vec![Vec::new(); n],
            q: Vec::new(),
        }))
    }

    /// Sets each particle's travel from the velocities `v` (inverse masses `w`) at the start of a
    /// step of `dt` and builds the pair lists from the positions `x`.
    pub(super) fn begin_step(&mut self, x: &[V3], v: &[V3], w: &[f64], dt: f64) {
        let m = mean_free(v, w);
        let bound = self.travel;
        self.step_travel = v
            .iter()
            .map(|&vi| {
                let u2 = dot(sub(vi, m), sub(vi, m));
                let u2 = if u2.is_nan() { u2 } else { u2.max(dot(m, m)) };
                let rel = u2.sqrt() * dt / self.d;
                if rel.is_finite() {
                    (TRAVEL_GROWTH as f64 * rel).max(TRAVEL_FLOOR as f64).min(bound)
                } else {
                    bound
                }
            })
            .collect();
        let top = self.step_travel.iter().copied().fold(0.0, f64::max);
        let reach = self.d + 2.0 * top * self.d;
        let skip = self.skip * self.d;
        let cell = |p: V3| p.map(|c| (c / reach).floor() as i64);
        let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
        for (i, &p) in x.iter().enumerate() {
            grid.entry(cell(p)).or_default().push(i);
        }
        for (i, list) in self.lists.iter_mut().enumerate() {
            list.clear();
            let c = cell(x[i]);
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let Some(bucket) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else {
                            continue;
                        };
                        for &j in bucket {
                            let near = |a: V3, b: V3, r: f64| dot(sub(a, b), sub(a, b)) <= r * r;
                            let rest_neighbour = self.cloth_of[i] == self.cloth_of[j] && near(self.rest[i], self.rest[j], skip);
                            let pair = self.d + (self.step_travel[i] + self.step_travel[j]) * self.d;
                            if j > i && near(x[i], x[j], pair) && !rest_neighbour {
                                list.push(j);
                            }
                        }
                    }
                }
            }
            list.sort_unstable();
        }
    }

    /// The speed clamp after predict, for a step of `substeps` substeps of length `h`.
    pub(super) fn clamp(&mut self, x: &[V3], v: &mut [V3], p: &mut [V3], w: &[f64], substeps: u32, h: f64) {
        let m = mean_free(v, w);
        for i in 0..v.len() {
            let limit = self.step_travel[i] * self.d / (substeps as f64 * h);
            let u = sub(v[i], m);
            let s = dot(u, u).sqrt();
            if !(w[i] > 0.0 && s > limit) {
                continue;
            }
            let slowed: V3 = std::array::from_fn(|k| m[k] + u[k] * limit / s);
            // Never faster than before (the clamp only slows a particle down).
            if dot(slowed, slowed) <= dot(v[i], v[i]) {
                v[i] = slowed;
                for k in 0..3 {
                    p[i][k] = x[i][k] + h * v[i][k];
                }
            }
        }
        self.q = p.to_vec();
    }

    /// Adds the contact of `i` with partner `j` to `s`, if `i` is free and they touch.
    fn contact(&self, i: usize, j: usize, x: &[V3], p: &[V3], w: &[f64], s: &mut Sums) {
        if w[i] <= 0.0 {
            return;
        }
        let v = sub(p[i], p[j]);
        let dist2 = dot(v, v);
        let r = sub(self.rest[i], self.rest[j]);
        let rest2 = if self.cloth_of[i] == self.cloth_of[j] {
            dot(r, r)
        } else {
            f64::INFINITY
        };
        let md = self.d.min(rest2.sqrt());
        if dist2 > rest2 || dist2 >= md * md {
            return;
        }
        let dist = dist2.sqrt();
        let n = if dist > 0.0 {
            v.map(|c| c / dist)
        } else if rest2.is_finite() && rest2 > 0.0 {
            r.map(|c| c / rest2.sqrt())
        } else {
            COINCIDENT.map(|c| if i < j { c } else { -c })
        };
        let share = w[i] / (w[i] + w[j]);
        let (di, dj) = (sub(p[i], x[i]), sub(p[j], x[j]));
        let amount = if self.response == Response::MovementSpeed {
            let vn = dot(sub(di, dj), n);
            if vn < 0.0 {
                s.approaching += 1.0;
                -vn * share
            } else {
                0.0
            }
        } else {
            (md - dist) * share
        };
        for k in 0..3 {
            s.c[k] += n[k] * amount;
            s.f[k] += dj[k];
            s.n[k] += n[k];
        }
        s.gap += dist - md;
        s.count += 1.0;
    }

    /// The pair pass and the correction of the predictions `p` after the constraint sweeps;
    /// `b` are the damping rates (may be empty).
    pub(super) fn respond(&self, x: &[V3], p: &mut [V3], w: &[f64], b: &[f64], h: f64) {
        let mut sums = vec![Sums::default(); p.len()];
        for (i, list) in self.lists.iter().enumerate() {
            for &j in list {
                self.contact(i, j, x, p, w, &mut sums[i]);
                self.contact(j, i, x, p, w, &mut sums[j]);
            }
        }
        for (i, s) in sums.iter().enumerate() {
            if s.count == 0.0 || w[i] <= 0.0 {
                continue;
            }
            let k = s.count;
            let kc = if self.response == Response::MovementSpeed && s.approaching > 0.0 {
                s.approaching
            } else {
                k
            };
            let mut t: V3 = std::array::from_fn(|a| {
                p[i][a] + s.c[a] * f64::from(RELAXATION) / kc + self.friction * (s.f[a] / k - (p[i][a] - x[i][a])) / 2.0
            });
            if self.response == Response::Vccpbd {
                let q = self.q[i];
                let tq = sub(t, q);
                if dot(tq, tq) >= (BOX_RADIUS as f64 * self.d).powi(2) {
                    t = q;
                } else {
                    let nl = dot(s.n, s.n).sqrt().max(f64::MIN_POSITIVE);
                    let nh = s.n.map(|c| c / nl);
                    let beta = (b.get(i).copied().unwrap_or(0.0) * h).min(1.0);
                    let amt = beta * dot(sub(t, x[i]), nh) + beta * beta * s.gap / k / 4.0;
                    t = std::array::from_fn(|a| t[a] - nh[a] * amt);
                }
            }
            p[i] = t;
        }
    }

    /// Particles with a non-neighbour (another cloth, or rest distance above `1.5 d`) closer
    /// than `0.9 d`, in percent (the world's "average collision" measure, brute force).
    pub(super) fn penetration_pct(&self, x: &[V3]) -> f64 {
        let lim = 0.9 * self.d;
        let far = 1.5 * self.d;
        let n = x.len();
        let hit = (0..n)
            .filter(|&i| {
                (0..n).any(|j| {
                    let r = sub(self.rest[i], self.rest[j]);
                    let neighbour = self.cloth_of[i] == self.cloth_of[j] && dot(r, r) <= far * far;
                    let v = sub(x[i], x[j]);
                    j != i && !neighbour && dot(v, v) < lim * lim
                })
            })
            .count();
        if n == 0 {
            0.0
        } else {
            100.0 * hit as f64 / n as f64
        }
    }
}
