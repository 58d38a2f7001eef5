//! Ignored tests that write demo pictures to /tmp for looking at by eye:
//! `cargo test --lib render::demo_tests -- --ignored`.

use super::*;
use std::f32::consts::PI;

/// A square cloth of `n` x `n` vertices and side `side`, draped over a sphere of `radius`
/// resting on the floor `y = 0`: it follows the sphere from the top out to the polar angle
/// `phi_max`, then hangs, flaring slightly, with folds that deepen toward the hem, and pools on
/// the floor. Wound so its front faces up.
fn draped_cloth(n: usize, side: f32, radius: f32) -> MeshItem {
    let phi_max = 1.0f32;
    let cap = radius * phi_max;
    let lift = 0.02 * radius;
    let mut positions = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            let u = (i as f32 / (n - 1) as f32 - 0.5) * side;
            let v = (j as f32 / (n - 1) as f32 - 0.5) * side;
            let r = (u * u + v * v).sqrt();
            let theta = v.atan2(u);
            let (rho, y) = if r <= cap {
                let phi = r / radius;
                ((radius + lift) * phi.sin(), radius + (radius + lift) * phi.cos())
            } else {
                let rho_c = (radius + lift) * phi_max.sin();
                let y_c = radius + (radius + lift) * phi_max.cos();
                let hang = r - cap;
                let wave = 0.5 + 0.5 * (9.0 * theta).sin();
                let fold = 1.0 + 0.3 * wave * (hang / radius).min(1.0);
                let rho = (rho_c + 0.45 * hang) * fold;
                let y = y_c - 0.9 * hang;
                if y > 0.01 {
                    (rho, y)
                } else {
                    (rho + (0.01 - y), 0.01) // the rest lies on the floor
                }
            };
            positions.push([rho * theta.cos(), y, rho * theta.sin()]);
        }
    }
    let mut triangles = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = (j * n + i) as u32;
            let (b, c, d) = (a + 1, a + n as u32, a + n as u32 + 1);
            triangles.push([a, c, b]);
            triangles.push([b, c, d]);
        }
    }
    MeshItem {
        positions,
        triangles,
        color: [186, 58, 52],
    }
}

/// Strands from the upper half of a head sphere, combed down over it and hanging.
fn hair(center: [f32; 3], radius: f32, count: usize, points: usize) -> Vec<LineItem> {
    let mut strands = Vec::new();
    let golden = PI * (3.0 - 5f32.sqrt());
    for k in 0..count {
        // Roots spread evenly over the cap above the ears (Fibonacci lattice).
        let y = 1.0 - (k as f32 + 0.5) / count as f32 * 0.9;
        let ring = (1.0 - y * y).sqrt();
        let a = golden * k as f32;
        let dir = [ring * a.cos(), y, ring * a.sin()];
        if dir[2] > 0.55 && dir[1] < 0.7 {
            continue; // leave the face free
        }
        let mut line = Vec::with_capacity(points);
        let length = 1.6 * radius;
        let step = length / (points - 1) as f32;
        let mut p = [
            center[0] + dir[0] * radius,
            center[1] + dir[1] * radius,
            center[2] + dir[2] * radius,
        ];
        let horizontal = [dir[0], 0.0, dir[2]];
        for s in 0..points {
            line.push(p);
            let rel = [p[0] - center[0], p[1] - center[1], p[2] - center[2]];
            let wave = 0.1 * (s as f32 * 0.6 + k as f32).sin();
            let d = if rel[1] > -0.15 * radius {
                // On the head: slide down the surface (gravity projected on the tangent plane).
                let len = (rel[0] * rel[0] + rel[1] * rel[1] + rel[2] * rel[2]).sqrt();
                let nrm = [rel[0] / len, rel[1] / len, rel[2] / len];
                let t = [nrm[1] * nrm[0], -1.0 + nrm[1] * nrm[1], nrm[1] * nrm[2]];
                let tl = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
                if tl < 0.2 {
                    horizontal
                } else {
                    [t[0] / tl + wave * nrm[2], t[1] / tl, t[2] / tl - wave * nrm[0]]
                }
            } else {
                // Below the head: fall, flaring a little outward.
                [horizontal[0] * 0.12 + wave * 0.3, -1.0, horizontal[2] * 0.12]
            };
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            p = [p[0] + d[0] / l * step, p[1] + d[1] / l * step, p[2] + d[2] / l * step];
            // Keep strands resting on the scalp while on the head.
            let rel = [p[0] - center[0], p[1] - center[1], p[2] - center[2]];
            let len = (rel[0] * rel[0] + rel[1] * rel[1] + rel[2] * rel[2]).sqrt();
            let shell = radius * (1.01 + 0.0004 * (k % 50) as f32);
            if rel[1] > -0.15 * radius || len < shell {
                let f = shell / len.max(1e-6);
                p = [center[0] + rel[0] * f, center[1] + rel[1] * f, center[2] + rel[2] * f];
            }
        }
        let shade = (k % 7) as u8 * 4;
        strands.push(LineItem {
            points: line,
            color: [92 + shade, 58 + shade / 2, 30],
            width_px: 1.3,
        });
    }
    strands
}

#[test]
#[ignore]
fn demo_cloth_over_sphere() {
    let radius = 0.7;
    let cloth = draped_cloth(60, 2.8, radius);
    let ball = MeshItem {
        color: [214, 206, 190],
        ..{
            let (positions, triangles) = shapes::uv_sphere([0.0, radius, 0.0], radius, 48);
            MeshItem {
                positions,
                triangles,
                color: [0; 3],
            }
        }
    };
    let scene = RenderScene {
        meshes: vec![cloth, ball],
        lines: vec![],
        background: DEFAULT_BACKGROUND,
    };
    let opts = RenderOptions {
        width: 640,
        height: 480,
        ..RenderOptions::default()
    };
    let img = render(&scene, &opts).unwrap();
    img.write_png(std::path::Path::new("/tmp/weft_render_demo.png")).unwrap();
}

#[test]
#[ignore]
fn demo_hair_on_head() {
    let head = [0.0, 1.0, 0.0];
    let (positions, triangles) = shapes::uv_sphere(head, 0.5, 64);
    let skin = MeshItem {
        positions,
        triangles,
        color: [226, 188, 160],
    };
    let scene = RenderScene {
        meshes: vec![skin],
        lines: hair(head, 0.5, 1500, 24),
        background: DEFAULT_BACKGROUND,
    };
    let opts = RenderOptions {
        width: 480,
        height: 480,
        ..RenderOptions::default()
    };
    let img = render(&scene, &opts).unwrap();
    img.write_png(std::path::Path::new("/tmp/weft_render_hair.png")).unwrap();
}

#[test]
#[ignore]
fn demo_sheet_and_gif() {
    let radius = 0.7;
    let draped = draped_cloth(40, 2.8, radius);
    let (positions, triangles) = shapes::uv_sphere([0.0, radius, 0.0], radius, 40);
    let ball = MeshItem {
        positions,
        triangles,
        color: [214, 206, 190],
    };
    let opts = RenderOptions {
        width: 240,
        height: 180,
        camera: Some(Camera::framing_for_aspect([-1.6, 0.0, -1.6], [1.6, 2.4, 1.6], 240.0 / 180.0)),
        ..RenderOptions::default()
    };
    // Frames of a sheet falling from flat (above the ball) onto it.
    let frames: Vec<Image> = (0..8)
        .map(|f| {
            let s = f as f32 / 7.0;
            let positions = draped
                .positions
                .iter()
                .map(|p| {
                    let flat = [p[0] * 0.8, 2.0 * radius + 0.8, p[2] * 0.8];
                    [
                        flat[0] + (p[0] - flat[0]) * s,
                        flat[1] + (p[1] - flat[1]) * s,
                        flat[2] + (p[2] - flat[2]) * s,
                    ]
                })
                .collect();
            let cloth = MeshItem {
                positions,
                ..draped.clone()
            };
            let scene = RenderScene {
                meshes: vec![cloth, ball.clone()],
                lines: vec![],
                background: DEFAULT_BACKGROUND,
            };
            render(&scene, &opts).unwrap()
        })
        .collect();
    let sheet = contact_sheet(&frames, 4, true).unwrap();
    sheet.write_png(std::path::Path::new("/tmp/weft_render_sheet.png")).unwrap();
    write_gif(std::path::Path::new("/tmp/weft_render_anim.gif"), &frames, 12).unwrap();
}

/// A sinusoidally waved 60x60 banner, seen so that both of its sides show.
#[test]
#[ignore]
fn demo_waved_banner() {
    let n = 60;
    let mut positions = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (u, v) = (i as f32 / (n - 1) as f32, j as f32 / (n - 1) as f32);
            let x = u * 2.0 - 1.0;
            let z = 0.35 * (u * 2.5 * PI).sin() * (0.4 + 0.6 * u);
            positions.push([x, 0.2 + v * 1.2, z]);
        }
    }
    let mut triangles = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = (j * n + i) as u32;
            let (b, c, d) = (a + 1, a + n as u32, a + n as u32 + 1);
            triangles.push([a, b, c]);
            triangles.push([b, d, c]);
        }
    }
    let banner = MeshItem {
        positions,
        triangles,
        color: [52, 110, 190],
    };
    let pole = MeshItem::from_shape(shapes::capsule([-1.02, 0.0, 0.0], [-1.02, 1.5, 0.0], 0.025, 16), [120, 110, 100]);
    let scene = RenderScene {
        meshes: vec![banner, pole],
        lines: vec![],
        background: DEFAULT_BACKGROUND,
    };
    let camera = Camera {
        eye: [2.6, 1.5, 1.3],
        target: [0.0, 0.75, 0.0],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: 40.0,
    };
    let opts = RenderOptions {
        width: 560,
        height: 420,
        camera: Some(camera),
        ..RenderOptions::default()
    };
    let img = render(&scene, &opts).unwrap();
    img.write_png(std::path::Path::new("/tmp/weft_render_banner.png")).unwrap();
}
