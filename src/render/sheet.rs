//! Contact sheets: many frames of a run tiled into one picture, optionally numbered.
//!
//! Layout: `c = min(columns, n)` columns and `r = ceil(n / c)` rows of equal cells with a
//! [`SHEET_GAP`]-pixel dark gutter around and between them, so the sheet is
//! `c w + (c + 1) gap` by `r h + (r + 1) gap` pixels. Labels are each frame's index in the
//! slice, drawn with a built-in 5x7 digit font on a darkened patch at the cell's top-left.

use super::Image;
use crate::{Result, WeftError};

/// Gutter width in pixels.
pub const SHEET_GAP: u32 = 4;
/// Gutter colour.
const GUTTER: [u8; 3] = [48, 50, 56];
/// Largest sheet, in pixels.
const MAX_SHEET_PIXELS: u64 = 1 << 28;

/// 5x7 bitmaps of the digits 0-9, one byte per row, bit 4 = leftmost column.
const DIGITS: [[u8; 7]; 10] = [
    [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E],
    [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E],
    [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F],
    [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E],
    [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02],
    [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E],
    [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E],
    [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
    [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E],
    [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C],
];

/// Tiles `frames` (all the same size) into one picture with `columns` columns; with `labels`,
/// each cell shows its frame's index.
pub fn contact_sheet(frames: &[Image], columns: u32, labels: bool) -> Result<Image> {
    let first = frames
        .first()
        .ok_or_else(|| WeftError::param("frames", 0, "need at least one frame"))?;
    if columns == 0 {
        return Err(WeftError::param("columns", 0, "must be at least 1"));
    }
    for (k, f) in frames.iter().enumerate() {
        f.check()?;
        if (f.width, f.height) != (first.width, first.height) {
            return Err(WeftError::param(
                format!("frames[{k}] size"),
                format!("{}x{}", f.width, f.height),
                format!("every frame must be {}x{} like frames[0]", first.width, first.height),
            ));
        }
    }
    let n = frames.len() as u64;
    let cols = (columns as u64).min(n);
    let rows = n.div_ceil(cols);
    let (fw, fh, gap) = (first.width as u64, first.height as u64, SHEET_GAP as u64);
    let width = cols * fw + (cols + 1) * gap;
    let height = rows * fh + (rows + 1) * gap;
    if width * height > MAX_SHEET_PIXELS || width > u32::MAX as u64 || height > u32::MAX as u64 {
        return Err(WeftError::param(
            "contact sheet size",
            format!("{width}x{height}"),
            format!("must have at most {MAX_SHEET_PIXELS} pixels"),
        ));
    }
    let mut sheet = Image::new(width as u32, height as u32, GUTTER);
    for (k, f) in frames.iter().enumerate() {
        let (cx, cy) = (k as u64 % cols, k as u64 / cols);
        let x0 = (gap + cx * (fw + gap)) as usize;
        let y0 = (gap + cy * (fh + gap)) as usize;
        let row_bytes = 3 * fw as usize;
        for y in 0..fh as usize {
            let dst = 3 * ((y0 + y) * width as usize + x0);
            sheet.rgb[dst..dst + row_bytes].copy_from_slice(&f.rgb[y * row_bytes..(y + 1) * row_bytes]);
        }
        if labels {
            let cell = Cell {
                x0,
                y0,
                w: fw as usize,
                h: fh as usize,
            };
            draw_label(&mut sheet, cell, &k.to_string());
        }
    }
    Ok(sheet)
}

/// A cell's place on the sheet.
#[derive(Clone, Copy)]
struct Cell {
    x0: usize,
    y0: usize,
    w: usize,
    h: usize,
}

/// Draws `text` (digits) at the top-left of `cell`, clipped to it.
fn draw_label(sheet: &mut Image, cell: Cell, text: &str) {
    let scale = (cell.w.min(cell.h) / 120).clamp(1, 4);
    let (margin, advance) = (2 * scale, 6 * scale);
    let patch_w = (text.len() * advance + 3 * scale).min(cell.w);
    let patch_h = (7 * scale + 2 * margin).min(cell.h);
    let sheet_w = sheet.width as usize;
    let mut put = |x: usize, y: usize, f: &dyn Fn([u8; 3]) -> [u8; 3]| {
        if x < cell.w && y < cell.h {
            let i = 3 * ((cell.y0 + y) * sheet_w + cell.x0 + x);
            let old = [sheet.rgb[i], sheet.rgb[i + 1], sheet.rgb[i + 2]];
            sheet.rgb[i..i + 3].copy_from_slice(&f(old));
        }
    };
    for y in 0..patch_h {
        for x in 0..patch_w {
            put(x, y, &|c| c.map(|v| v / 3));
        }
    }
    for (k, ch) in text.bytes().enumerate() {
        let Some(glyph) = ch.checked_sub(b'0').and_then(|d| DIGITS.get(d as usize)) else {
            continue;
        };
        for (gy, bits) in glyph.iter().enumerate() {
            for gx in 0..5 {
                if bits & (0x10 >> gx) == 0 {
                    continue;
                }
                for sy in 0..scale {
                    for sx in 0..scale {
                        let x = margin + k * advance + gx * scale + sx;
                        put(x, margin + gy * scale + sy, &|_| [250, 250, 250]);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sheet_size_follows_the_layout_formula() {
        let frames: Vec<Image> = (0..7).map(|k| Image::new(30, 20, [k * 30, 0, 0])).collect();
        let s = contact_sheet(&frames, 3, false).unwrap();
        assert_eq!(s.width, 3 * 30 + 4 * SHEET_GAP);
        assert_eq!(s.height, 3 * 20 + 4 * SHEET_GAP);
        assert_eq!(s.rgb.len(), 3 * (s.width * s.height) as usize);
        // Frame 4 sits in column 1, row 1.
        let (x, y) = (SHEET_GAP + 30 + SHEET_GAP + 5, SHEET_GAP + 20 + SHEET_GAP + 5);
        assert_eq!(s.pixel(x, y), Some([120, 0, 0]));
        assert_eq!(s.pixel(1, 1), Some(GUTTER));
        // More columns than frames: one row only as wide as needed.
        let s = contact_sheet(&frames[..2], 5, true).unwrap();
        assert_eq!((s.width, s.height), (2 * 30 + 3 * SHEET_GAP, 20 + 2 * SHEET_GAP));
    }

    #[test]
    fn labels_draw_bright_digits_and_bad_input_is_an_error() {
        let frames: Vec<Image> = (0..12).map(|_| Image::new(40, 30, [0, 0, 200])).collect();
        let plain = contact_sheet(&frames, 4, false).unwrap();
        let labelled = contact_sheet(&frames, 4, true).unwrap();
        let bright = |img: &Image| img.rgb.chunks(3).filter(|p| p[0] > 240).count();
        assert_eq!(bright(&plain), 0);
        assert!(bright(&labelled) > 12 * 8);
        assert!(contact_sheet(&[], 2, true).is_err());
        assert!(contact_sheet(&frames, 0, true).is_err());
        let mixed = [Image::new(4, 4, [0; 3]), Image::new(5, 4, [0; 3])];
        assert!(contact_sheet(&mixed, 2, true).is_err());
    }
}
