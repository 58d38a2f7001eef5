//! One obstacle's contact slots for every particle, with a per-block "touched" flag.
//!
//! The slots are stored in blocks of eight particles,
//! `[cx; 8] [cy; 8] [cz; 8] [nx; 8] [ny; 8] [nz; 8] [a; 8]` ([`SLOT_BLOCK`] floats), so a
//! SIMD lane reads contiguous values and a parallel task owns whole blocks. "No contact" is the
//! zero normal.
//!
//! **Touched flags.** At 1M particles the slots take 28 MB, and most blocks of a cloth over an
//! obstacle hold no contact. `touched[b]` is `false` exactly when block `b` is all `+0.0` (no
//! contact, zero approach speed; [`block_nonzero`]), so the passes after the contact search
//! skip such blocks reading one byte instead of 96 bytes of normals (a block without a set
//! normal changes nothing in any pass, so skipping it is exact), and the contact search skips
//! writing a block that stays empty. Every write of a block goes with the update of its flag
//! ([`Slots::write`], the generators through `obstacles::for_blocks`).

use crate::data::lanes::{load, F32s, LANES};
use wide::u32x8;

/// Floats per block of eight slots.
pub const SLOT_BLOCK: usize = 7 * LANES;

/// One obstacle's slots (`data`, blocks of [`SLOT_BLOCK`] floats) and per-block flags.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Slots {
    /// The slot blocks.
    pub data: Vec<f32>,
    /// `touched[b]`: block `b` is not all `+0.0` ([`block_nonzero`]).
    pub touched: Vec<bool>,
}

impl Slots {
    /// `blocks` empty blocks.
    pub fn new(blocks: usize) -> Slots {
        Slots {
            data: vec![0.0; blocks * SLOT_BLOCK],
            touched: vec![false; blocks],
        }
    }

    /// Slots holding `data` (whole blocks), each block's flag set from its contents.
    pub fn from_data(data: Vec<f32>) -> Slots {
        let touched = data.chunks(SLOT_BLOCK).map(block_nonzero).collect();
        Slots { data, touched }
    }

    /// Writes slot `i` (as [`write_slot`]) and updates its block's flag.
    pub fn write(&mut self, i: usize, point: [f32; 3], normal: [f32; 3]) {
        write_slot(&mut self.data, i, point, normal);
        let b = i / LANES;
        self.touched[b] = block_nonzero(&self.data[b * SLOT_BLOCK..(b + 1) * SLOT_BLOCK]);
    }

    /// Sets the approach speed of slot `i`.
    pub fn set_approach(&mut self, i: usize, a: f32) {
        let b = i / LANES;
        self.data[b * SLOT_BLOCK + 6 * LANES + i % LANES] = a;
        self.touched[b] = block_nonzero(&self.data[b * SLOT_BLOCK..(b + 1) * SLOT_BLOCK]);
    }

    /// Does every flag equal [`block_nonzero`] of its block?
    pub fn flags_consistent(&self) -> bool {
        self.data.len() == self.touched.len() * SLOT_BLOCK
            && self.data.chunks(SLOT_BLOCK).zip(&self.touched).all(|(b, &t)| block_nonzero(b) == t)
    }

    /// Number of blocks.
    pub fn blocks(&self) -> usize {
        self.touched.len()
    }
}

/// What the passes read of one obstacle's slots: the slot blocks and their flags, owned
/// ([`Slots`]) or a chunk's part of them ([`SlotsView`], block 0 being the chunk's first).
pub trait SlotBlocks {
    /// The slot blocks.
    fn data(&self) -> &[f32];
    /// The blocks' touched flags.
    fn touched(&self) -> &[bool];
}

impl SlotBlocks for Slots {
    fn data(&self) -> &[f32] {
        &self.data
    }
    fn touched(&self) -> &[bool] {
        &self.touched
    }
}

/// A run of one obstacle's slot blocks and their flags, borrowed.
#[derive(Clone, Copy, Debug, Default)]
pub struct SlotsView<'a> {
    /// The slot blocks.
    pub data: &'a [f32],
    /// Their flags.
    pub touched: &'a [bool],
}

impl SlotBlocks for SlotsView<'_> {
    fn data(&self) -> &[f32] {
        self.data
    }
    fn touched(&self) -> &[bool] {
        self.touched
    }
}

/// One obstacle's slots as a raw view, so that the tasks of a chunk-by-chunk pass can each
/// take the blocks of their own chunk ([`blocks`](Self::blocks)).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SlotsPtr {
    data: *mut f32,
    touched: *mut bool,
    blocks: usize,
}

// SAFETY: two pointers and a length; blocks are handed to one task each (see `blocks`).
unsafe impl Send for SlotsPtr {}
// SAFETY: as above.
unsafe impl Sync for SlotsPtr {}

impl SlotsPtr {
    /// Captures `slots` (whole blocks, one flag each).
    pub(crate) fn new(slots: &mut Slots) -> Self {
        assert_eq!(slots.data.len(), slots.touched.len() * SLOT_BLOCK);
        SlotsPtr {
            data: slots.data.as_mut_ptr(),
            touched: slots.touched.as_mut_ptr(),
            blocks: slots.touched.len(),
        }
    }

    /// Blocks `first .. first + count` and their flags.
    ///
    /// # Safety
    /// The captured slots outlive the slices and nothing else reads or writes them through any
    /// other reference meanwhile, and no other live slice from this view covers these blocks
    /// (each chunk of a pass takes its own blocks).
    pub(crate) unsafe fn blocks<'a>(self, first: usize, count: usize) -> (&'a mut [f32], &'a mut [bool]) {
        assert!(first + count <= self.blocks);
        // SAFETY: in bounds (checked above) and exclusive by the caller's guarantee.
        unsafe {
            (
                std::slice::from_raw_parts_mut(self.data.add(first * SLOT_BLOCK), count * SLOT_BLOCK),
                std::slice::from_raw_parts_mut(self.touched.add(first), count),
            )
        }
    }
}

/// Writes slot `i` of `blocks` (blocks start at particle `first`).
#[inline]
pub fn write_slot(blocks: &mut [f32], i: usize, point: [f32; 3], normal: [f32; 3]) {
    let (b, l) = (i / LANES, i % LANES);
    for k in 0..3 {
        blocks[b * SLOT_BLOCK + k * LANES + l] = point[k];
        blocks[b * SLOT_BLOCK + (3 + k) * LANES + l] = normal[k];
    }
    blocks[b * SLOT_BLOCK + 6 * LANES + l] = 0.0;
}

/// Reads slot `i`: `(point, normal)`.
#[inline]
pub fn read_slot(blocks: &[f32], i: usize) -> ([f32; 3], [f32; 3]) {
    let (b, l) = (i / LANES, i % LANES);
    let g = |k: usize| blocks[b * SLOT_BLOCK + k * LANES + l];
    ([g(0), g(1), g(2)], [g(3), g(4), g(5)])
}

/// Approach speed of slot `i`.
#[inline]
pub fn read_approach(blocks: &[f32], i: usize) -> f32 {
    blocks[i / LANES * SLOT_BLOCK + 6 * LANES + i % LANES]
}

/// Does block `b` hold a contact in any of `slots`? (Its flag; the passes skip whole blocks
/// that do not.)
#[inline]
pub fn block_touched<S: SlotBlocks>(slots: &[S], b: usize) -> bool {
    slots.iter().any(|s| s.touched()[b])
}

/// Is any float of `block` other than `+0.0` (bitwise: `-0.0` and NaN count)? The value of a
/// block's touched flag.
#[inline]
pub fn block_nonzero(block: &[f32]) -> bool {
    or_bits(block) != 0
}

/// Does one slot block (its [`SLOT_BLOCK`] floats) hold a normal other than zero? The same as
/// "any normal component `!= 0.0`" (NaN counts as set), computed without branches: the bits
/// of every component but the sign, or-ed together.
#[inline]
pub fn normals_set(block: &[f32]) -> bool {
    // Shifting left drops the sign bit; it distributes over the `or`.
    or_bits(&block[3 * LANES..6 * LANES]) << 1 != 0
}

/// The bits of every value of `values` or-ed together: a vector `or` a group of [`LANES`]
/// values (a plain fold left a slot block's last 24 values to a scalar loop), then the rest.
#[inline]
fn or_bits(values: &[f32]) -> u32 {
    let groups = values.chunks_exact(LANES);
    let rest = groups.remainder().iter().fold(0u32, |a, &c| a | c.to_bits());
    let mut acc = u32x8::ZERO;
    for g in groups {
        acc |= bytemuck::cast::<F32s, u32x8>(load(g, 0));
    }
    acc.to_array().iter().fold(rest, |a, &b| a | b)
}

/// The next particle index from `i` (of a run starting at particle `start`, `len` long) that
/// may hold a contact: `i` itself unless it starts a whole block without any.
#[inline]
pub(crate) fn skip_untouched<S: SlotBlocks>(slots: &[S], start: usize, len: usize, mut i: usize) -> usize {
    while (start + i).is_multiple_of(LANES) && i + LANES <= len && !block_touched(slots, (start + i) / LANES) {
        i += LANES;
    }
    i
}
