//! Stage 2 of the obstacle step for a mesh obstacle: the contacts of one block of eight
//! particles ([`obstacles`](super::obstacles) module doc; SEEDS.md section D).
//!
//! For each live particle of the block (a real particle with inverse mass `w > 0`) the path
//! is `x - u h -> p` in the obstacle's frame and its query box `Q` is the path's box grown by
//! the contact reach ([`query_box`]). Three cases, cheapest first:
//!
//! 1. **Far from the mesh.** Every face's box lies inside the mesh's box, so when `Q` misses
//!    the mesh box on some axis (`Q.hi < lo` or `Q.lo > hi`, exact `f32` comparisons) no face
//!    can overlap `Q`: no contact, and the particle's kept candidate list is not even read.
//!    This is the paper's first test ("is the particle inside the box around the object at
//!    all?") taken per particle. A NaN coordinate never counts as far: such a particle goes
//!    the full way, which finds no contact either.
//! 2. **Kept list** ([`CachedFaces`]): the faces gathered for a box around an earlier path
//!    still cover `Q`, so the narrowphase tests them; when the box was empty of faces there
//!    is nothing to test.
//! 3. **Gather**: the broadphase is asked again (and the list kept for the coming steps).
//!
//! With the paper's face memory every live particle runs the memory rule around cases 2-3
//! (a far particle must also forget its face), and the fresh-search reference (no kept lists,
//! no far test) runs the full search for every live particle. All cases give the contacts of
//! the plain search ([`step_contact`](super::obstacle_mesh::step_contact)), so the pass
//! changes the cost, not the answer; each particle writes only its own slot, list and memory,
//! so the result does not depend on the thread count.
//!
//! The block's slots are cleared, each contact is written into its lane, and the approach
//! speeds are filled only when some lane holds a contact (a block without contact has all
//! approach speeds `0`, as [`fill_approach`](k::fill_approach) would write).

use super::face_cache::CachedFaces;
use super::mesh::TriMesh;
use super::narrow::query_box;
use super::obstacle_kernels::{self as k, GenInput};
use super::obstacle_mesh::{remembered_with, MeshBroadphase};
use crate::lanes::LANES;

/// One substep's contact pass of a mesh obstacle (module doc).
pub(crate) struct MeshPass<'a> {
    /// The mesh at its place for this substep.
    pub mesh: &'a TriMesh,
    /// Its broadphase.
    pub bp: &'a MeshBroadphase,
    /// The particles' paths and reaches.
    pub input: GenInput<'a>,
    /// Particle velocities (for the approach speeds).
    pub vel: [&'a [f32]; 3],
    /// The obstacle's velocity.
    pub u: [f32; 3],
    /// Face memory on (the memories are the per-particle `mem` slices).
    pub remember: bool,
    /// Fresh search for every particle: the reference of the kept lists and the far test.
    pub fresh: bool,
}

/// The eight values of padded array `a` for block `b`.
#[inline]
fn lanes(a: &[f32], b: usize) -> [f32; LANES] {
    let s = &a[b * LANES..(b + 1) * LANES];
    std::array::from_fn(|l| s[l])
}

impl MeshPass<'_> {
    /// The contacts of block `b` into `out` (the block's slot floats); `mem` and `cache` are
    /// the block's face memories (empty without memory) and kept lists (eight entries).
    pub(crate) fn block(&self, b: usize, out: &mut [f32], mem: &mut [u32], cache: &mut [CachedFaces], scratch: &mut Vec<u32>) {
        let g = &self.input;
        let x = [lanes(g.x[0], b), lanes(g.x[1], b), lanes(g.x[2], b)];
        let p = [lanes(g.p[0], b), lanes(g.p[1], b), lanes(g.p[2], b)];
        let sh = g.shift;
        let (w, reach) = (lanes(g.w, b), lanes(g.reach, b));
        let (mlo, mhi) = self.mesh.bounds();
        let skip_far = !self.remember && !self.fresh;
        out.fill(0.0);
        let mut touched = false;
        for l in 0..LANES {
            let live = b * LANES + l < g.n && w[l] > 0.0;
            if !live {
                continue;
            }
            let xl = [x[0][l] - sh[0], x[1][l] - sh[1], x[2][l] - sh[2]];
            let pl = [p[0][l], p[1][l], p[2][l]];
            let (lo, hi) = query_box(xl, pl, reach[l]);
            let far = (hi[0] < mlo[0]) | (hi[1] < mlo[1]) | (hi[2] < mlo[2]) | (lo[0] > mhi[0]) | (lo[1] > mhi[1]) | (lo[2] > mhi[2]);
            if skip_far && far {
                continue;
            }
            let entry = &mut cache[l];
            let mut search = || entry.contact_in(self.mesh, self.bp, xl, pl, reach[l], (lo, hi), !self.fresh, scratch);
            let c = if self.remember {
                remembered_with(self.mesh, &mut mem[l], xl, pl, reach[l], 2.0 * reach[l], search)
            } else {
                search()
            };
            if let Some(c) = c {
                k::write_slot(out, l, c.point, c.normal);
                touched = true;
            }
        }
        if touched {
            k::fill_approach(out, b, self.vel, self.u);
        }
    }
}
