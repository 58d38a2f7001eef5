//! Per-particle candidate faces kept from step to step (a Verlet list for mesh obstacles).
//!
//! A step `x -> p` of reach `r` can touch only the faces whose box overlaps its query box
//! `Q = box(x, p) + r` ([`query_box`]), and the narrowphase tests exactly those faces
//! ([`best_contact`]). Asking the broadphase for them every step costs far more than the test
//! itself when the particle rests on the obstacle. So each particle keeps a **gathered box**
//! `G = Q + m` (its query box grown by a margin `m`) and the list of faces whose box overlaps
//! `G`. While a later query box lies inside `G` (`G.lo <= Q.lo` and `Q.hi <= G.hi` on every
//! axis, exact `f32` comparisons), every face overlapping `Q` overlaps `G` (intervals are
//! closed and `f32` comparisons are exact), so it is in the list; the list is filtered by
//! `Q` and handed to the same narrowphase with the same total order of contacts. The contacts
//! are therefore bit for bit those of the uncached search, whatever the broadphase and
//! whatever the order of the list. When `Q` leaves `G` the particle gathers again.
//!
//! The margin bounds the motion of the coming steps: [`margin`] is `MARGIN_REACH` reaches plus
//! [`MARGIN_STEPS`] times the step's largest coordinate change, so a particle moving steadily
//! gathers at most every few steps and a resting one keeps its list. A mesh that moves (a new
//! [`TriMesh::stamp`]) empties every list ([`FaceCache::sync`]). A particle owns its entry,
//! so the cache changes nothing about thread-count independence.

use super::face_broadphase::FaceBroadphase;
use super::mesh::TriMesh;
use super::narrow::{query_box, Contact};
use super::obstacle_mesh::best_contact;

/// The gathered box reaches this many contact reaches beyond the query box.
pub const MARGIN_REACH: f32 = 1.0;
/// ... plus this many times the step's largest coordinate change.
pub const MARGIN_STEPS: f32 = 4.0;

/// The margin of a gathered box for the step `x -> p` of reach `reach` (module doc).
#[inline]
pub fn margin(x: [f32; 3], p: [f32; 3], reach: f32) -> f32 {
    let d = (0..3).fold(0.0f32, |m, k| m.max((p[k] - x[k]).abs()));
    MARGIN_REACH * reach + MARGIN_STEPS * d
}

/// Faces a list keeps inline (in the entry itself, so the entries of neighbouring particles
/// share cache lines); longer lists live in the entry's own heap vector.
pub const INLINE_FACES: usize = 12;

/// One particle's gathered box and the faces whose box overlaps it.
#[derive(Debug, Clone)]
pub struct CachedFaces {
    lo: [f32; 3],
    hi: [f32; 3],
    len: u32,
    inline: [u32; INLINE_FACES],
    spill: Vec<u32>,
}

impl Default for CachedFaces {
    /// An empty entry: its box contains nothing, so the first query gathers.
    fn default() -> Self {
        CachedFaces {
            lo: [f32::INFINITY; 3],
            hi: [f32::NEG_INFINITY; 3],
            len: 0,
            inline: [0; INLINE_FACES],
            spill: Vec::new(),
        }
    }
}

impl CachedFaces {
    /// Forgets the list (keeps its storage).
    pub fn clear(&mut self) {
        self.lo = [f32::INFINITY; 3];
        self.hi = [f32::NEG_INFINITY; 3];
        self.len = 0;
        self.spill.clear();
    }

    /// Does the gathered box contain `[lo, hi]`?
    #[inline]
    fn holds(&self, lo: [f32; 3], hi: [f32; 3]) -> bool {
        // `&` rather than `&&`: one branch for the six comparisons
        (self.lo[0] <= lo[0])
            & (self.lo[1] <= lo[1])
            & (self.lo[2] <= lo[2])
            & (hi[0] <= self.hi[0])
            & (hi[1] <= self.hi[1])
            & (hi[2] <= self.hi[2])
    }

    /// The faces gathered (at least every face overlapping the gathered box).
    pub fn faces(&self) -> &[u32] {
        match self.len as usize {
            n if n <= INLINE_FACES => &self.inline[..n],
            _ => &self.spill,
        }
    }

    /// Keeps `faces` as the list.
    fn store(&mut self, faces: &[u32]) {
        self.len = faces.len() as u32;
        self.spill.clear();
        if faces.len() <= INLINE_FACES {
            self.inline[..faces.len()].copy_from_slice(faces);
        } else {
            self.spill.extend_from_slice(faces);
        }
    }

    /// The contact of the step `x -> p` within `reach`: exactly
    /// [`step_contact`](super::obstacle_mesh::step_contact), using and refreshing the list
    /// (module doc). A new gathering grows the query box by [`margin`] when `keep`, by
    /// nothing otherwise (a fresh search every step, the reference).
    #[allow(clippy::too_many_arguments)]
    pub fn step_contact<B: FaceBroadphase + ?Sized>(
        &mut self,
        mesh: &TriMesh,
        bp: &B,
        x: [f32; 3],
        p: [f32; 3],
        reach: f32,
        keep: bool,
        scratch: &mut Vec<u32>,
    ) -> Option<Contact> {
        self.contact_in(mesh, bp, x, p, reach, query_box(x, p, reach), keep, scratch)
    }

    /// [`step_contact`](Self::step_contact) given the step's query box `q`
    /// (`query_box(x, p, reach)`).
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub(crate) fn contact_in<B: FaceBroadphase + ?Sized>(
        &mut self,
        mesh: &TriMesh,
        bp: &B,
        x: [f32; 3],
        p: [f32; 3],
        reach: f32,
        (lo, hi): ([f32; 3], [f32; 3]),
        keep: bool,
        scratch: &mut Vec<u32>,
    ) -> Option<Contact> {
        if keep && self.holds(lo, hi) {
            return match self.len {
                0 => None,
                _ => best_contact(mesh, self.faces(), x, p, reach, lo, hi),
            };
        }
        self.gather(mesh, bp, x, p, reach, (lo, hi), keep, scratch)
    }

    /// [`contact_in`](Self::contact_in) when the list does not cover the query box (or is
    /// not kept): gathers afresh.
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    fn gather<B: FaceBroadphase + ?Sized>(
        &mut self,
        mesh: &TriMesh,
        bp: &B,
        x: [f32; 3],
        p: [f32; 3],
        reach: f32,
        (lo, hi): ([f32; 3], [f32; 3]),
        keep: bool,
        scratch: &mut Vec<u32>,
    ) -> Option<Contact> {
        let margin = if keep { margin(x, p, reach) } else { 0.0 };
        let (glo, ghi) = (lo.map(|v| v - margin), hi.map(|v| v + margin));
        bp.candidates(mesh, glo, ghi, scratch);
        // A NaN or a margin lost to rounding leaves a box that does not hold the query: then
        // this step uses the fresh candidates and keeps nothing (so does a fresh search).
        if !(keep && margin >= 0.0 && (0..3).all(|k| glo[k] <= lo[k] && hi[k] <= ghi[k])) {
            self.clear();
            return best_contact(mesh, scratch, x, p, reach, lo, hi);
        }
        let n = mesh.face_count();
        scratch.retain(|&f| (f as usize) < n && mesh.face_overlaps(f, glo, ghi));
        self.store(scratch);
        (self.lo, self.hi) = (glo, ghi);
        best_contact(mesh, self.faces(), x, p, reach, lo, hi)
    }
}

/// The candidate lists of every particle against one mesh obstacle.
#[derive(Debug, Clone, Default)]
pub struct FaceCache {
    stamp: u64,
    entries: Vec<CachedFaces>,
}

impl FaceCache {
    /// Sizes the cache to `n` particles and empties every list if the mesh state (`stamp`)
    /// or the particle count changed.
    pub fn sync(&mut self, n: usize, stamp: u64) {
        if self.entries.len() != n {
            self.entries = vec![CachedFaces::default(); n];
        } else if self.stamp != stamp {
            self.entries.iter_mut().for_each(CachedFaces::clear);
        }
        self.stamp = stamp;
    }

    /// The per-particle entries.
    pub fn entries_mut(&mut self) -> &mut [CachedFaces] {
        &mut self.entries
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collide::dressform::dress_form;
    use crate::collide::face_broadphase::BruteForce;
    use crate::collide::obstacle_mesh::step_contact;

    #[test]
    fn cached_contacts_equal_the_uncached_search_along_random_walks() {
        let m = dress_form(1200).unwrap();
        let bp = BruteForce::new(&m);
        let (lo, hi) = m.bounds();
        let mut rng = crate::test_rng::unit(7);
        let mut scratch = Vec::new();
        let (mut hits, mut kept) = (0, 0);
        for _ in 0..60 {
            let mut c = CachedFaces::default();
            let mut x = [0, 1, 2].map(|k| lo[k] + (hi[k] - lo[k]) * rng());
            for _ in 0..80 {
                let d = [0; 3].map(|_| (rng() - 0.5) * 0.006);
                let p = [0, 1, 2].map(|k| x[k] + d[k]);
                let before = c.faces().len();
                let got = c.step_contact(&m, &bp, x, p, 0.004, true, &mut scratch);
                let want = step_contact(&m, &bp, x, p, 0.004, &mut Vec::new());
                assert_eq!(got, want, "x {x:?} p {p:?}");
                hits += got.is_some() as usize;
                kept += (before == c.faces().len()) as usize;
                x = p;
            }
        }
        assert!(hits > 100, "the walks must meet the surface: {hits}");
        assert!(kept > 1000, "the lists must be reused: {kept}");
    }

    #[test]
    fn sync_empties_on_a_new_stamp_and_nan_gives_the_uncached_answer() {
        let m = dress_form(600).unwrap();
        let bp = BruteForce::new(&m);
        let mut cache = FaceCache::default();
        cache.sync(2, m.stamp());
        let e = &mut cache.entries_mut()[0];
        let top = [0.0, crate::collide::dressform::HEIGHT + 0.001, 0.0];
        e.step_contact(&m, &bp, top, top, 0.004, true, &mut Vec::new());
        assert!(!e.faces().is_empty());
        cache.sync(2, m.stamp());
        assert!(!cache.entries_mut()[0].faces().is_empty());
        cache.sync(2, m.stamp() + 1);
        assert!(cache.entries_mut()[0].faces().is_empty());
        let e = &mut cache.entries_mut()[1];
        for (x, p) in [([f32::NAN; 3], top), (top, [f32::NAN; 3]), (top, top)] {
            let got = e.step_contact(&m, &bp, x, p, 0.004, true, &mut Vec::new());
            assert_eq!(got, step_contact(&m, &bp, x, p, 0.004, &mut Vec::new()));
        }
    }

    /// A cloth draped on a form gives bitwise the same run with the kept lists (and the
    /// particles skipped as far from the mesh, `mesh_pass.rs`) as with a fresh broadphase search for every particle every
    /// substep (on one thread against two), for every broadphase, with and without face
    /// memory.
    #[test]
    fn a_draping_world_runs_bitwise_alike_with_and_without_the_cache() {
        use crate::collide::obstacles::{BroadphaseKind, Obstacle};
        use crate::SolverParams;
        let run = |kind, memory, fresh| {
            let params = SolverParams {
                dt: 1.0 / 400.0,
                substeps: 2,
                iterations: 1,
                // the reference runs on one thread, the fast path on two
                threads: if fresh { 1 } else { 2 },
                ..SolverParams::default()
            };
            // wider than the form: blocks at the row ends lie outside the mesh box
            let mut w = sheet_over_form(params, [24, 48], 0.012, [-0.282, -0.138]);
            w.add_obstacle(Obstacle::mesh(dress_form(600).unwrap(), kind, memory).unwrap())
                .unwrap();
            w.obstacles.set_fresh_search(fresh);
            let mut touched = 0;
            for _ in 0..120 {
                w.step(1.0 / 400.0).unwrap();
                touched = touched.max(w.obstacle_contacts());
            }
            let mut pos = Vec::new();
            w.positions_interleaved(&mut pos);
            (pos, touched)
        };
        for kind in [BroadphaseKind::Grid(Some([5, 9, 5])), BroadphaseKind::Bvh, BroadphaseKind::Hash] {
            for memory in [false, true] {
                let (kept, touched) = run(kind, memory, false);
                assert!(touched > 50, "the cloth must land on the form: {touched}");
                let (fresh, _) = run(kind, memory, true);
                assert!(
                    kept.iter().zip(&fresh).all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits)),
                    "{kind:?} memory {memory}"
                );
            }
        }
    }

    /// A horizontal cotton sheet of `rows x cols` released 5 mm above the dress form's top,
    /// its corner at `(x, z)`, friction 0.3; the caller adds the form.
    fn sheet_over_form(params: crate::SolverParams, [rows, cols]: [u32; 2], spacing: f32, [x, z]: [f32; 2]) -> crate::World {
        use crate::{ClothDesc, Effects, Fabric, World};
        let mut w = World::new(params, Effects::gravity()).unwrap();
        w.add_cloth(&ClothDesc {
            rows,
            cols,
            spacing,
            origin: [x, crate::collide::dressform::HEIGHT + 0.005, z],
            u: [1.0, 0.0, 0.0],
            v: [0.0, 0.0, 1.0],
            fabric: Fabric::preset("cotton").unwrap(),
            ..ClothDesc::default()
        })
        .unwrap();
        w.set_friction(0.3).unwrap();
        w
    }

    /// `weft reproduce landovsky` counts one step of `h` with one substep as one iteration
    /// and says the physics is bit for bit that of steps of `4 h` with four substeps: the
    /// obstacle stages (and their kept lists) see the same substeps either way.
    #[test]
    fn steps_of_one_substep_equal_a_quarter_of_steps_of_four() {
        use crate::collide::obstacles::{BroadphaseKind, Obstacle};
        use crate::SolverParams;
        let run = |dt: f32, substeps: u32, steps: usize| {
            let params = SolverParams {
                dt,
                substeps,
                iterations: 1,
                ..SolverParams::default()
            };
            let mut w = sheet_over_form(params, [40, 30], 0.009, [-0.13, -0.18]);
            let form = Obstacle::mesh(dress_form(4800).unwrap(), BroadphaseKind::Grid(Some([15, 30, 15])), false);
            w.add_obstacle(form.unwrap()).unwrap();
            for _ in 0..steps {
                w.step(dt).unwrap();
            }
            let mut pos = Vec::new();
            w.positions_interleaved(&mut pos);
            (pos, w.obstacle_contacts())
        };
        let (four, touched) = run(1.0 / 200.0, 4, 40);
        let (one, touched_one) = run(1.0 / 800.0, 1, 160);
        assert!(touched > 20, "the sheet must land on the form: {touched}");
        assert_eq!(touched, touched_one);
        assert!(four.iter().zip(&one).all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits)));
    }
}
