//! Animated GIF output: frames quantized to 256 colours each (NeuQuant, through the `gif`
//! crate), looping forever, written through a temporary file renamed into place.

use super::image::write_atomically;
use super::Image;
use crate::{Result, WeftError};
use std::path::Path;

/// Quantizer speed handed to the `gif` crate (1 = best, 30 = fastest; 10 is its suggestion).
const QUANTIZE_SPEED: i32 = 10;

/// Writes `frames` (all the same size, at most 65535 pixels on a side) as a looping GIF with
/// `delay_centiseconds` between frames.
pub fn write_gif(path: &Path, frames: &[Image], delay_centiseconds: u16) -> Result<()> {
    let first = frames
        .first()
        .ok_or_else(|| WeftError::param("frames", 0, "need at least one frame"))?;
    let too_big = |v: u32| WeftError::param("gif size", v, "GIF frames are at most 65535 pixels on a side");
    let w = u16::try_from(first.width).map_err(|_| too_big(first.width))?;
    let h = u16::try_from(first.height).map_err(|_| too_big(first.height))?;
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
    write_atomically(path, |file| {
        let mut enc = gif::Encoder::new(file, w, h, &[]).map_err(|e| e.to_string())?;
        enc.set_repeat(gif::Repeat::Infinite).map_err(|e| e.to_string())?;
        for f in frames {
            let mut frame = gif::Frame::from_rgb_speed(w, h, &f.rgb, QUANTIZE_SPEED);
            frame.delay = delay_centiseconds;
            enc.write_frame(&frame).map_err(|e| e.to_string())?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gif_is_readable_with_all_frames() {
        let frames: Vec<Image> = (0..3u8)
            .map(|k| {
                let mut img = Image::new(16, 12, [20, 30, 40]);
                img.rgb[..3].copy_from_slice(&[200, 10 * k, 0]);
                img
            })
            .collect();
        let path = std::env::temp_dir().join(format!("weft_anim_{}.gif", std::process::id()));
        write_gif(&path, &frames, 7).unwrap();
        let mut opts = gif::DecodeOptions::new();
        opts.set_color_output(gif::ColorOutput::RGBA);
        let mut dec = opts.read_info(std::fs::File::open(&path).unwrap()).unwrap();
        assert_eq!((dec.width(), dec.height()), (16, 12));
        let mut count = 0;
        while let Some(frame) = dec.read_next_frame().unwrap() {
            assert_eq!(frame.delay, 7);
            assert_eq!(frame.buffer.len(), 16 * 12 * 4);
            // The background colour survives quantization closely.
            let p = &frame.buffer[4 * 20..4 * 20 + 3];
            assert!(p.iter().zip([20u8, 30, 40]).all(|(a, b)| a.abs_diff(b) <= 8), "{p:?}");
            count += 1;
        }
        assert_eq!(count, 3);
        std::fs::remove_file(&path).unwrap();
    }

    #[test]
    fn bad_gif_input_is_an_error() {
        let dir = std::env::temp_dir();
        assert!(write_gif(&dir.join("weft_empty.gif"), &[], 5).is_err());
        let wide = Image::new(70_000, 1, [0; 3]);
        assert!(write_gif(&dir.join("weft_wide.gif"), &[wide], 5).is_err());
        let mixed = [Image::new(4, 4, [0; 3]), Image::new(4, 5, [0; 3])];
        assert!(write_gif(&dir.join("weft_mixed.gif"), &mixed, 5).is_err());
    }
}
