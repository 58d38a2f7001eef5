//! The block passes of the obstacle stages: a placed shape's contacts with one block of
//! eight particles ([`shape_block`]), the walk over every block in parallel tasks or serially
//! with each thread's candidate-face scratch (`for_blocks`), and a small list of per-obstacle
//! values held on the stack (`on_stack`).

use rayon::prelude::*;

use crate::data::lanes::LANES;
use crate::obstacles::kernels::{self as k, GenInput, Slots, SLOT_BLOCK};
use crate::obstacles::mesh::face_cache::CacheBlock;

/// Blocks of eight particles per parallel task.
const BLOCKS_PER_TASK: usize = 32;

/// The contacts of block `b` (its slots `out`, its flag `was`) with a placed shape, and their
/// approach speeds from the velocities `vel` (indexed as `g`'s arrays); returns the block's
/// new flag. A block the pre-test finds far gets exactly the empty block the full test writes.
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn shape_block(
    shape: &crate::model::shapes::Shape,
    g: &GenInput,
    b: usize,
    out: &mut [f32],
    was: bool,
    vel: [&[f32]; 3],
    u: [f32; 3],
    simd: bool,
) -> bool {
    let may = if simd {
        k::shape_may_touch_simd(shape, g, b)
    } else {
        k::shape_may_touch_scalar(shape, g, b)
    };
    if !may {
        if was {
            out.fill(0.0);
        }
        return false;
    }
    if simd {
        k::shape_block_simd(shape, g, b, out);
        k::fill_approach_simd(out, b, vel, u);
    } else {
        k::shape_block_scalar(shape, g, b, out);
        k::fill_approach(out, b, vel, u);
    }
    k::block_nonzero(out)
}

/// Runs `f(block, slots of the block, its touched flag, face memory of the block, face cache
/// of the block, scratch)` over every block of eight particles, in parallel tasks of
/// [`BLOCKS_PER_TASK`] blocks or serially, and sets the block's flag to what `f` returns (`f`
/// returns [`k::block_nonzero`] of the block, or `false` for a block it leaves or makes empty).
/// `memory` is empty or one entry per particle, `cache` empty or one [`CacheBlock`] per block
/// (handed to `f` as a slice of one). Each thread's scratch holds at least `faces` entries
/// (the mesh's face count, the most candidates a query can give but for a broadphase's
/// duplicates), reserved once, so its size does not depend on which thread ran which block.
pub(super) fn for_blocks<F>(slots: &mut Slots, memory: &mut [u32], cache: &mut [CacheBlock], parallel: bool, faces: usize, f: F)
where
    F: Fn(usize, &mut [f32], bool, &mut [u32], &mut [CacheBlock], &mut Vec<u32>) -> bool + Sync + Send,
{
    let task = SLOT_BLOCK * BLOCKS_PER_TASK;
    let per_task = LANES * BLOCKS_PER_TASK;
    let tasks = slots.data.len().div_ceil(task);
    let run = |t: usize, chunk: &mut [f32], flags: &mut [bool], mem: &mut [u32], cache: &mut [CacheBlock], scratch: &mut Vec<u32>| {
        for (j, (out, flag)) in chunk.chunks_mut(SLOT_BLOCK).zip(flags.iter_mut()).enumerate() {
            let lanes = j * LANES..(j + 1) * LANES;
            let m = if mem.is_empty() { &mut [][..] } else { &mut mem[lanes.clone()] };
            let c = if cache.is_empty() { &mut [][..] } else { &mut cache[j..j + 1] };
            *flag = f(t * BLOCKS_PER_TASK + j, out, *flag, m, c, scratch);
        }
    };
    // `memory` and `cache` cut into one piece per task, or one empty piece per task when empty,
    // without collecting the pieces (a step allocates nothing).
    fn pieces<T: Send>(v: &mut [T], per_task: usize, tasks: usize) -> impl IndexedParallelIterator<Item = &mut [T]> + '_ {
        if v.is_empty() {
            rayon::iter::Either::Left((0..tasks).into_par_iter().map(|_| <&mut [T]>::default()))
        } else {
            rayon::iter::Either::Right(v.par_chunks_mut(per_task))
        }
    }
    fn pieces_serial<T>(v: &mut [T], per_task: usize, tasks: usize) -> impl Iterator<Item = &mut [T]> + '_ {
        if v.is_empty() {
            rayon::iter::Either::Left((0..tasks).map(|_| <&mut [T]>::default()))
        } else {
            rayon::iter::Either::Right(v.chunks_mut(per_task))
        }
    }
    let Slots { data, touched } = slots;
    if parallel {
        let mems = pieces(memory, per_task, tasks);
        let caches = pieces(cache, BLOCKS_PER_TASK, tasks);
        data.par_chunks_mut(task)
            .zip(touched.par_chunks_mut(BLOCKS_PER_TASK))
            .zip(mems.zip(caches))
            .enumerate()
            .for_each(|(t, ((chunk, flags), (mem, c)))| with_scratch(faces, |s| run(t, chunk, flags, mem, c, s)));
    } else {
        let blocks = data.chunks_mut(task).zip(touched.chunks_mut(BLOCKS_PER_TASK));
        let mems = pieces_serial(memory, per_task, tasks);
        let caches = pieces_serial(cache, BLOCKS_PER_TASK, tasks);
        for (t, ((chunk, flags), (mem, c))) in blocks.zip(mems.zip(caches)).enumerate() {
            with_scratch(faces, |s| run(t, chunk, flags, mem, c, s));
        }
    }
}

/// Runs `f` on the items, held in a stack array when there are at most 8 (so a substep with
/// a few obstacles allocates nothing), else in a `Vec`.
pub(super) fn on_stack<T: Copy + Default, R>(items: impl ExactSizeIterator<Item = T>, f: impl FnOnce(&[T]) -> R) -> R {
    let n = items.len();
    if n <= 8 {
        let mut buf = [T::default(); 8];
        for (b, v) in buf.iter_mut().zip(items) {
            *b = v;
        }
        f(&buf[..n])
    } else {
        f(&items.collect::<Vec<T>>())
    }
}

thread_local! {
    /// Each thread's candidate-face scratch for [`for_blocks`], kept across steps so that a
    /// step allocates nothing once it has grown.
    static SCRATCH: std::cell::Cell<Vec<u32>> = const { std::cell::Cell::new(Vec::new()) };
}

/// Runs `f` with this thread's scratch (taken out, so a nested call gets a fresh one), holding
/// at least `reserve` entries.
fn with_scratch<R>(reserve: usize, f: impl FnOnce(&mut Vec<u32>) -> R) -> R {
    let mut s = SCRATCH.with(|c| c.take());
    if s.capacity() < reserve {
        s.reserve(reserve - s.len());
    }
    let r = f(&mut s);
    SCRATCH.with(|c| c.set(s));
    r
}
