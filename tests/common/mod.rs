//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod glb;

/// Cases per property: `default`, or `PROPTEST_CASES` when set (for long local runs;
/// `ProptestConfig::with_cases` alone ignores it).
pub fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(default)
}

use weft::{ClothDesc, Effects, Fabric, PinSpec, SolverParams, World};

/// A world with one cloth.
pub fn world_with(desc: &ClothDesc, params: SolverParams, effects: Effects) -> World {
    let mut w = World::new(params, effects).expect("valid world");
    w.add_cloth(desc).expect("valid cloth");
    w
}

/// A hanging cloth pinned at two corners.
pub fn hanging(rows: u32, cols: u32) -> ClothDesc {
    ClothDesc {
        rows,
        cols,
        spacing: 0.05,
        pins: vec![PinSpec::FirstRowCorners],
        fabric: Fabric::preset("cotton").unwrap(),
        ..Default::default()
    }
}

/// Bit patterns of every position and velocity.
pub fn state_bits(w: &World) -> Vec<u32> {
    let p = w.positions();
    let v = w.velocities();
    p.iter().chain(v.iter()).flat_map(|a| a.iter().map(|f| f.to_bits())).collect()
}

/// Fraction of a PNG file's pixels that differ from the renderer's background.
#[cfg(feature = "render")]
pub fn non_background_fraction(png_path: &std::path::Path) -> f32 {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(png_path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let img = weft::render::Image {
        width: info.width,
        height: info.height,
        rgb: buf[..info.buffer_size()].to_vec(),
    };
    img.non_background_fraction(weft::render::DEFAULT_BACKGROUND)
}

/// Fraction of a PNG file's pixels for which `keep(r, g, b)` holds.
pub fn colour_fraction(png_path: &std::path::Path, keep: impl Fn(u8, u8, u8) -> bool) -> f32 {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(png_path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let px = &buf[..info.buffer_size()];
    let n = px.chunks(3).filter(|p| keep(p[0], p[1], p[2])).count();
    n as f32 / (info.width * info.height) as f32
}
