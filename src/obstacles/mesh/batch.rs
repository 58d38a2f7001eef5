//! Contacts for a whole particle set against one mesh, in parallel (rayon) with a serial twin.
//!
//! Particles are independent in this phase: particle `i`'s contact depends only on its own
//! start `(x, y, z)[i]`, prediction `(px, py, pz)[i]`, the thickness and the mesh. Each thread
//! writes only its own output slots, so the parallel result equals the serial one bit for bit,
//! whatever the number of threads. Inputs are checked first (equal lengths, finite values,
//! thickness `>= 0`, broadphase built for this mesh state), so the per-particle kernels never
//! meet bad data.

use crate::obstacles::mesh::broadphase::FaceBroadphase;
use crate::obstacles::mesh::face_memory::contact_with_memory;
use crate::obstacles::mesh::narrow::{mesh_contact_with, Contact};
use crate::obstacles::mesh::TriMesh;
use crate::{Result, WeftError};
use rayon::prelude::*;

/// Particles per rayon task (keeps the per-task candidate buffer busy).
const MIN_CHUNK: usize = 64;

/// Three coordinate arrays of equal length (structure of arrays).
#[derive(Debug, Clone, Copy)]
pub struct Soa3<'a> {
    /// x coordinates.
    pub x: &'a [f32],
    /// y coordinates.
    pub y: &'a [f32],
    /// z coordinates.
    pub z: &'a [f32],
}

impl Soa3<'_> {
    #[inline]
    fn get(&self, i: usize) -> [f32; 3] {
        [self.x[i], self.y[i], self.z[i]]
    }
    fn check(&self, name: &'static str, n: usize) -> Result<()> {
        for (arr, which) in [(self.x, "x"), (self.y, "y"), (self.z, "z")] {
            if arr.len() != n {
                return Err(WeftError::BufferLength {
                    name,
                    got: arr.len(),
                    expected: n,
                });
            }
            if let Some(i) = arr.iter().position(|v| !v.is_finite()) {
                return Err(WeftError::param(format!("{name}.{which}[{i}]"), arr[i], "must be finite"));
            }
        }
        Ok(())
    }
}

fn check<B: FaceBroadphase + ?Sized>(mesh: &TriMesh, bp: &B, start: &Soa3, pred: &Soa3, th: f32) -> Result<usize> {
    let n = start.x.len();
    start.check("start", n)?;
    pred.check("predicted", n)?;
    crate::error::non_negative("thickness", th)?;
    if bp.stamp() != mesh.stamp() {
        return Err(WeftError::param(
            "broadphase",
            bp.describe(),
            "was built for another mesh state (rebuild or refit it after moving the mesh)",
        ));
    }
    Ok(n)
}

/// Serial twin of [`contacts_par`].
pub fn contacts_serial<B: FaceBroadphase + ?Sized>(
    mesh: &TriMesh,
    bp: &B,
    start: Soa3,
    pred: Soa3,
    th: f32,
    out: &mut Vec<Option<Contact>>,
) -> Result<()> {
    let n = check(mesh, bp, &start, &pred, th)?;
    let mut scratch = Vec::new();
    out.clear();
    out.extend((0..n).map(|i| mesh_contact_with(mesh, bp, start.get(i), pred.get(i), th, &mut scratch)));
    Ok(())
}

/// Every particle's first contact with `mesh` (see [`mesh_contact_with`]), in parallel.
pub fn contacts_par<B: FaceBroadphase + Sync + ?Sized>(
    mesh: &TriMesh,
    bp: &B,
    start: Soa3,
    pred: Soa3,
    th: f32,
    out: &mut Vec<Option<Contact>>,
) -> Result<()> {
    let n = check(mesh, bp, &start, &pred, th)?;
    out.clear();
    out.resize(n, None);
    out.par_iter_mut()
        .enumerate()
        .with_min_len(MIN_CHUNK)
        .for_each_init(Vec::new, |scratch, (i, o)| {
            *o = mesh_contact_with(mesh, bp, start.get(i), pred.get(i), th, scratch);
        });
    Ok(())
}

fn check_memory(memory: &[u32], n: usize, band: f32) -> Result<()> {
    if memory.len() != n {
        return Err(WeftError::BufferLength {
            name: "face_memory",
            got: memory.len(),
            expected: n,
        });
    }
    crate::error::non_negative("face memory band", band)?;
    Ok(())
}

/// Serial twin of [`contacts_with_memory_par`].
#[allow(clippy::too_many_arguments)]
pub fn contacts_with_memory_serial<B: FaceBroadphase + ?Sized>(
    mesh: &TriMesh,
    bp: &B,
    start: Soa3,
    pred: Soa3,
    th: f32,
    band: f32,
    memory: &mut [u32],
    out: &mut Vec<Option<Contact>>,
) -> Result<()> {
    let n = check(mesh, bp, &start, &pred, th)?;
    check_memory(memory, n, band)?;
    let mut scratch = Vec::new();
    out.clear();
    out.extend(
        memory
            .iter_mut()
            .enumerate()
            .map(|(i, m)| contact_with_memory(mesh, bp, m, start.get(i), pred.get(i), th, band, &mut scratch).contact),
    );
    Ok(())
}

/// Every particle's contact using the paper's face memory
/// ([`contact_with_memory`]), in parallel; `memory` holds one face index per particle.
#[allow(clippy::too_many_arguments)]
pub fn contacts_with_memory_par<B: FaceBroadphase + Sync + ?Sized>(
    mesh: &TriMesh,
    bp: &B,
    start: Soa3,
    pred: Soa3,
    th: f32,
    band: f32,
    memory: &mut [u32],
    out: &mut Vec<Option<Contact>>,
) -> Result<()> {
    let n = check(mesh, bp, &start, &pred, th)?;
    check_memory(memory, n, band)?;
    out.clear();
    out.resize(n, None);
    out.par_iter_mut()
        .zip(memory.par_iter_mut())
        .enumerate()
        .with_min_len(MIN_CHUNK)
        .for_each_init(Vec::new, |scratch, (i, (o, m))| {
            *o = contact_with_memory(mesh, bp, m, start.get(i), pred.get(i), th, band, scratch).contact;
        });
    Ok(())
}
