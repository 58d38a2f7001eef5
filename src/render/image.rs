//! The 8-bit RGB picture and its PNG output.
//!
//! Files are written to a temporary name in the same directory and renamed into place, so a
//! reader never sees a half-written picture (rename within one directory is atomic on POSIX).

use crate::{Result, WeftError};
use std::io::Write;
use std::path::{Path, PathBuf};

/// A picture: `width * height` pixels, three bytes (red, green, blue) each, row by row from the
/// top-left corner.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixel bytes, `3 * width * height` of them, sRGB-encoded.
    pub rgb: Vec<u8>,
}

/// Two pixels whose channels all differ by at most this much count as the same colour in
/// [`Image::non_background_fraction`]; it covers the renderer's gentle background gradient.
pub const BACKGROUND_TOLERANCE: u8 = 12;

impl Image {
    /// A `width` x `height` picture filled with `background`.
    pub fn new(width: u32, height: u32, background: [u8; 3]) -> Image {
        let n = width as usize * height as usize;
        let mut rgb = Vec::with_capacity(3 * n);
        for _ in 0..n {
            rgb.extend_from_slice(&background);
        }
        Image { width, height, rgb }
    }

    /// Checks that the size is non-zero and the buffer length matches it.
    pub fn check(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(WeftError::param(
                "image size",
                format!("{}x{}", self.width, self.height),
                "width and height must be at least 1",
            ));
        }
        let expected = 3 * self.width as usize * self.height as usize;
        if self.rgb.len() != expected {
            return Err(WeftError::BufferLength {
                name: "image.rgb",
                got: self.rgb.len(),
                expected,
            });
        }
        Ok(())
    }

    /// The pixel at column `x`, row `y` (`None` outside the picture).
    pub fn pixel(&self, x: u32, y: u32) -> Option<[u8; 3]> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let i = 3 * (y as usize * self.width as usize + x as usize);
        let p = self.rgb.get(i..i + 3)?;
        Some([p[0], p[1], p[2]])
    }

    /// Writes the picture as an 8-bit RGB PNG, through a temporary file renamed into place.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        self.check()?;
        write_atomically(path, |file| {
            let mut enc = png::Encoder::new(file, self.width, self.height);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut writer = enc.write_header().map_err(|e| e.to_string())?;
            writer.write_image_data(&self.rgb).map_err(|e| e.to_string())?;
            writer.finish().map_err(|e| e.to_string())
        })
    }

    /// Fraction of pixels (0 to 1) whose colour differs from `background` by more than
    /// [`BACKGROUND_TOLERANCE`] in some channel. An empty or malformed picture gives 0.
    pub fn non_background_fraction(&self, background: [u8; 3]) -> f32 {
        let n = self.rgb.len() / 3;
        if n == 0 {
            return 0.0;
        }
        let differs = self
            .rgb
            .chunks_exact(3)
            .filter(|p| p.iter().zip(background).any(|(&a, b)| a.abs_diff(b) > BACKGROUND_TOLERANCE))
            .count();
        differs as f32 / n as f32
    }
}

/// Runs `fill` on a temporary file beside `path`, then renames it to `path`. On any failure the
/// temporary file is removed and `path` is left as it was.
pub(crate) fn write_atomically(
    path: &Path,
    fill: impl FnOnce(&mut std::io::BufWriter<&std::fs::File>) -> std::result::Result<(), String>,
) -> Result<()> {
    let tmp = temp_name(path);
    let file = std::fs::File::create(&tmp).map_err(|e| WeftError::io(&tmp, e))?;
    let outcome = (|| {
        let mut buf = std::io::BufWriter::new(&file);
        fill(&mut buf).map_err(|m| WeftError::Io {
            path: path.display().to_string(),
            message: m,
        })?;
        buf.flush().map_err(|e| WeftError::io(path, e))?;
        drop(buf);
        file.sync_all().map_err(|e| WeftError::io(path, e))?;
        std::fs::rename(&tmp, path).map_err(|e| WeftError::io(path, e))
    })();
    if outcome.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    outcome
}

/// `dir/.name.<pid>.tmp` beside `path`.
fn temp_name(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "image".to_string());
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_round_trips_with_its_size_and_pixels() {
        let mut img = Image::new(7, 5, [10, 20, 30]);
        img.rgb[3 * (2 * 7 + 3)] = 255;
        let path = std::env::temp_dir().join(format!("weft_png_{}.png", std::process::id()));
        img.write_png(&path).unwrap();
        let file = std::io::BufReader::new(std::fs::File::open(&path).unwrap());
        let mut reader = png::Decoder::new(file).read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (7, 5));
        assert_eq!(info.color_type, png::ColorType::Rgb);
        assert_eq!(&buf[..info.buffer_size()], &img.rgb[..]);
        std::fs::remove_file(&path).unwrap();
    }

    #[test]
    fn bad_images_and_paths_are_errors_and_leave_no_temp_file() {
        let mut img = Image::new(4, 4, [0; 3]);
        img.rgb.pop();
        let dir = std::env::temp_dir();
        assert!(img.write_png(&dir.join("weft_bad.png")).is_err());
        assert!(Image::new(0, 3, [0; 3]).check().is_err());
        let img = Image::new(2, 2, [0; 3]);
        let missing = dir.join("weft_no_such_dir_xyz").join("a.png");
        assert!(matches!(img.write_png(&missing), Err(WeftError::Io { .. })));
        // A directory in place of the file: the rename fails and the temp file is cleaned up.
        let blocker = dir.join(format!("weft_blocker_{}", std::process::id()));
        std::fs::create_dir_all(blocker.join("x")).unwrap();
        assert!(img.write_png(&blocker).is_err());
        assert!(!temp_name(&blocker).exists());
        std::fs::remove_dir_all(&blocker).unwrap();
    }

    #[test]
    fn non_background_fraction_counts_differing_pixels() {
        let mut img = Image::new(10, 10, [100; 3]);
        assert_eq!(img.non_background_fraction([100; 3]), 0.0);
        for i in 0..25 {
            img.rgb[3 * i] = 200;
        }
        img.rgb[3 * 50 + 1] = 100 + BACKGROUND_TOLERANCE; // within tolerance
        assert!((img.non_background_fraction([100; 3]) - 0.25).abs() < 1e-6);
        assert_eq!(img.pixel(0, 0), Some([200, 100, 100]));
        assert_eq!(img.pixel(10, 0), None);
    }
}
