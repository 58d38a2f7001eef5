//! Lighting: how a surface point or a hair segment turns into a colour.
//!
//! All shading is done in linear light; colours given by the user are sRGB and are decoded
//! first, and the final picture is encoded back to sRGB after the supersamples are averaged.
//!
//! Surfaces (Blinn-Phong with a soft cloth sheen) under a three-part rig fixed to the camera,
//! so every view is lit the same way:
//! `c = base (A(n) + k_key s max(0, n·L_key) + k_fill max(0, n·L_fill) + k_rim (1 - n·v)^3)
//!      + k_spec s k_key max(0, n·h)^m`,
//! where `A(n)` is a hemisphere ambient (brighter for normals facing up than down), `s` is the
//! shadow factor in [0, 1] and `h = (L_key + v)/|L_key + v|`.
//!
//! Cloth is two-sided: at a back face the normal is flipped toward the camera and the base is
//! the desaturated, darker "back tint" so the underside of a cloth reads as such.
//!
//! Hair follows Kajiya and Kay (1989): a strand is a thin cylinder with tangent `t`; its diffuse
//! term is `sin(t, L) = sqrt(1 - (t·L)^2)` and its highlight is `sin(t, h)^p`, which
//! produces the bright band across a bundle of strands that makes lines read as hair.

use super::math::{add, dot, normalize_or, scale, sub};

/// Decodes one sRGB byte to linear light.
pub fn srgb_to_linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Decodes an sRGB colour to linear light.
pub fn color_to_linear(c: [u8; 3]) -> [f32; 3] {
    [srgb_to_linear(c[0]), srgb_to_linear(c[1]), srgb_to_linear(c[2])]
}

/// Encodes linear light back to sRGB bytes through a table.
pub struct SrgbEncoder {
    table: Vec<u8>,
}

/// Table resolution of [`SrgbEncoder`].
const ENCODE_STEPS: usize = 8192;

impl SrgbEncoder {
    /// Builds the table.
    pub fn new() -> SrgbEncoder {
        let table = (0..=ENCODE_STEPS)
            .map(|i| {
                let l = i as f32 / ENCODE_STEPS as f32;
                let s = if l <= 0.003_130_8 {
                    12.92 * l
                } else {
                    1.055 * l.powf(1.0 / 2.4) - 0.055
                };
                (s * 255.0 + 0.5).clamp(0.0, 255.0) as u8
            })
            .collect();
        SrgbEncoder { table }
    }

    /// Linear value (clamped to [0, 1]; NaN gives 0) to an sRGB byte.
    #[inline]
    pub fn encode(&self, l: f32) -> u8 {
        let i = (l.clamp(0.0, 1.0) * ENCODE_STEPS as f32 + 0.5) as usize;
        self.table[i.min(ENCODE_STEPS)]
    }
}

/// The camera-fixed light rig, in world space.
#[derive(Clone, Copy, Debug)]
pub struct Lights {
    /// Unit direction toward the key light.
    pub key: [f32; 3],
    /// Unit direction toward the fill light.
    pub fill: [f32; 3],
    /// World up, for the hemisphere ambient.
    pub up: [f32; 3],
}

const KEY: f32 = 0.95;
const FILL: f32 = 0.22;
const SKY: f32 = 0.18;
const GROUND: f32 = 0.05;
const RIM: f32 = 0.10;
const SPEC: f32 = 0.10;
const SHININESS: i32 = 24;
const HAIR_SPEC: f32 = 0.45;
const HAIR_SHININESS: i32 = 64;

impl Lights {
    /// The rig for a camera with basis `right`, `up`, `forward`: key from the upper left and
    /// in front, fill from the right, ambient from above.
    pub fn for_camera(right: [f32; 3], up: [f32; 3], forward: [f32; 3], world_up: [f32; 3]) -> Lights {
        let toward_camera = scale(forward, -1.0);
        let key = add(add(scale(right, -0.65), scale(up, 0.8)), scale(toward_camera, 0.45));
        let fill = add(add(scale(right, 0.8), scale(up, 0.1)), scale(toward_camera, 0.6));
        Lights {
            key: normalize_or(key, up),
            fill: normalize_or(fill, toward_camera),
            up: normalize_or(world_up, up),
        }
    }

    /// Colour of a surface point with unit normal `n` (already facing the viewer), unit
    /// direction to the eye `v`, linear base colour and shadow factor.
    #[inline]
    pub fn surface(&self, n: [f32; 3], v: [f32; 3], base: [f32; 3], shadow: f32) -> [f32; 3] {
        let up = dot(n, self.up);
        let ambient = GROUND + (SKY - GROUND) * (0.5 + 0.5 * up);
        let nk = dot(n, self.key).max(0.0);
        let nf = dot(n, self.fill).max(0.0);
        let nv = dot(n, v).clamp(0.0, 1.0);
        let rim = RIM * (1.0 - nv) * (1.0 - nv) * (1.0 - nv);
        let diffuse = ambient + KEY * shadow * nk + FILL * nf + rim;
        let h = normalize_or(add(self.key, v), n);
        let spec = if nk > 0.0 {
            SPEC * KEY * shadow * dot(n, h).max(0.0).powi(SHININESS)
        } else {
            0.0
        };
        [base[0] * diffuse + spec, base[1] * diffuse + spec, base[2] * diffuse + spec]
    }

    /// Colour of a hair segment with unit tangent `t`, unit direction to the eye `v`, linear
    /// base colour and a root-to-tip shade factor.
    #[inline]
    pub fn hair(&self, t: [f32; 3], v: [f32; 3], base: [f32; 3], shade: f32) -> [f32; 3] {
        let sin = |a: [f32; 3]| (1.0 - dot(t, a) * dot(t, a)).max(0.0).sqrt();
        let diffuse = (SKY + GROUND) * 0.5 + KEY * 0.8 * sin(self.key) + FILL * sin(self.fill);
        let h = normalize_or(add(self.key, v), v);
        let spec = HAIR_SPEC * sin(h).powi(HAIR_SHININESS);
        let base = scale(base, shade);
        [
            base[0] * diffuse + spec * (0.6 + 0.4 * base[0]),
            base[1] * diffuse + spec * (0.6 + 0.4 * base[1]),
            base[2] * diffuse + spec * (0.6 + 0.4 * base[2]),
        ]
    }
}

/// The colour used for the back of a surface: darker and desaturated toward its own grey.
pub fn back_tint(base: [f32; 3]) -> [f32; 3] {
    let grey = 0.2126 * base[0] + 0.7152 * base[1] + 0.0722 * base[2];
    let mixed = add(scale(base, 0.55), scale([grey; 3], 0.45));
    scale(mixed, 0.7)
}

/// Background colour (sRGB) of row `y` of `height`: a gentle vertical gradient around
/// `background`, lighter at the top, darker at the bottom, within
/// [`super::BACKGROUND_TOLERANCE`] of it everywhere.
pub fn background_row(background: [u8; 3], y: u32, height: u32) -> [u8; 3] {
    let t = if height > 1 { y as f32 / (height - 1) as f32 } else { 0.5 };
    let offset = (8.0 * (1.0 - 2.0 * t)).round() as i32;
    background.map(|c| (c as i32 + offset).clamp(0, 255) as u8)
}

/// Unit vector from `p` to `eye`.
#[inline]
pub fn to_eye(eye: [f32; 3], p: [f32; 3]) -> [f32; 3] {
    normalize_or(sub(eye, p), [0.0, 0.0, 1.0])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trips_every_byte() {
        let enc = SrgbEncoder::new();
        for c in 0..=255u8 {
            assert_eq!(enc.encode(srgb_to_linear(c)), c);
        }
        assert_eq!(enc.encode(f32::NAN), 0);
        assert_eq!(enc.encode(7.0), 255);
    }

    #[test]
    fn key_side_is_brighter_and_back_tint_is_darker() {
        let lights = Lights::for_camera([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]);
        let v = [0.0, 0.0, 1.0];
        let base = [0.5; 3];
        let lit = lights.surface(lights.key, v, base, 1.0);
        let away = lights.surface(scale(lights.key, -1.0), v, base, 1.0);
        let shadowed = lights.surface(lights.key, v, base, 0.0);
        assert!(lit[0] > 2.0 * away[0] && lit[0] > shadowed[0]);
        let b = back_tint([0.8, 0.2, 0.1]);
        assert!(b[0] < 0.8 && b[1] > 0.2 * 0.7 && b[0] - b[1] < 0.6);
        // Hair: a strand across the light is lit more than one pointing at it.
        let across = lights.hair([1.0, 0.0, 0.0], v, base, 1.0);
        let along = lights.hair(lights.key, v, base, 1.0);
        assert!(across[0] > along[0]);
    }

    #[test]
    fn background_gradient_stays_within_tolerance() {
        for y in 0..50 {
            let c = background_row([250, 3, 128], y, 50);
            for (a, b) in c.iter().zip([250u8, 3, 128]) {
                assert!(a.abs_diff(b) <= super::super::BACKGROUND_TOLERANCE);
            }
        }
        assert!(background_row([128; 3], 0, 50)[0] > background_row([128; 3], 49, 50)[0]);
    }
}
