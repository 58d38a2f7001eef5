//! Whole-pipeline tests of [`render`](super::render), plus an ignored demo that writes a picture.

use super::*;

const BG: [u8; 3] = DEFAULT_BACKGROUND;

fn mesh(shape: shapes::Shape, color: [u8; 3]) -> MeshItem {
    MeshItem::from_shape(shape, color)
}

fn plain(width: u32, height: u32, camera: Option<Camera>) -> RenderOptions {
    RenderOptions {
        width,
        height,
        supersample: 2,
        camera,
        shadows: false,
        ground_shadow: false,
    }
}

fn front_camera() -> Camera {
    Camera {
        eye: [0.0, 0.0, 3.0],
        target: [0.0; 3],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: 40.0,
    }
}

fn luminance(p: [u8; 3]) -> f32 {
    0.2126 * p[0] as f32 + 0.7152 * p[1] as f32 + 0.0722 * p[2] as f32
}

fn is_object(p: [u8; 3]) -> bool {
    p.iter().zip(BG).any(|(a, b)| a.abs_diff(b) > BACKGROUND_TOLERANCE)
}

#[test]
fn unit_sphere_fills_a_plausible_part_and_its_lit_side_is_brighter() {
    let scene = RenderScene {
        meshes: vec![mesh(shapes::uv_sphere([0.0; 3], 1.0, 48), [180, 70, 60])],
        lines: vec![],
        background: BG,
    };
    let img = render(&scene, &plain(128, 128, None)).unwrap();
    let frac = img.non_background_fraction(BG);
    assert!((0.2..0.8).contains(&frac), "fraction {frac}");
    // Centroid of the object, then mean brightness of its upper-left vs lower-right quadrant
    // (the key light sits at the camera's upper left).
    let (mut sx, mut sy, mut n) = (0.0, 0.0, 0.0);
    for y in 0..img.height {
        for x in 0..img.width {
            if is_object(img.pixel(x, y).unwrap()) {
                (sx, sy, n) = (sx + x as f32, sy + y as f32, n + 1.0);
            }
        }
    }
    let (cx, cy) = (sx / n, sy / n);
    let (mut lit, mut nl, mut dark, mut nd) = (0.0, 0.0, 0.0, 0.0);
    for y in 0..img.height {
        for x in 0..img.width {
            let p = img.pixel(x, y).unwrap();
            if !is_object(p) {
                continue;
            }
            let (fx, fy) = (x as f32, y as f32);
            if fx < cx && fy < cy {
                (lit, nl) = (lit + luminance(p), nl + 1.0);
            } else if fx > cx && fy > cy {
                (dark, nd) = (dark + luminance(p), nd + 1.0);
            }
        }
    }
    let (lit, dark) = (lit / nl, dark / nd);
    assert!(lit > dark * 1.3, "lit {lit} dark {dark}");
}

#[test]
fn quad_seen_from_behind_is_drawn_in_its_back_tint() {
    let color = [40, 160, 220];
    let away = mesh(shapes::plane_quad([0.0; 3], [0.0, 0.0, -1.0], 0.8), color);
    let toward = mesh(shapes::plane_quad([0.0; 3], [0.0, 0.0, 1.0], 0.8), color);
    let opts = plain(64, 64, Some(front_camera()));
    let back = render(
        &RenderScene {
            meshes: vec![away],
            lines: vec![],
            background: BG,
        },
        &opts,
    )
    .unwrap();
    let front = render(
        &RenderScene {
            meshes: vec![toward],
            lines: vec![],
            background: BG,
        },
        &opts,
    )
    .unwrap();
    assert!(back.non_background_fraction(BG) > 0.3);
    let (b, f) = (back.pixel(32, 32).unwrap(), front.pixel(32, 32).unwrap());
    assert!(luminance(b) < luminance(f), "back {b:?} front {f:?}");
    // The back tint is greyer: its blue-red spread is smaller.
    assert!((b[2] as i32 - b[0] as i32) < (f[2] as i32 - f[0] as i32));
}

#[test]
fn near_red_quad_hides_far_blue_quad_in_either_order() {
    let red = mesh(shapes::plane_quad([0.0, 0.0, 0.5], [0.0, 0.0, 1.0], 0.5), [230, 20, 20]);
    let blue = mesh(shapes::plane_quad([0.0, 0.0, -0.5], [0.0, 0.0, 1.0], 1.0), [20, 20, 230]);
    let opts = plain(64, 64, Some(front_camera()));
    for meshes in [vec![red.clone(), blue.clone()], vec![blue.clone(), red.clone()]] {
        let scene = RenderScene {
            meshes,
            lines: vec![],
            background: BG,
        };
        let img = render(&scene, &opts).unwrap();
        let centre = img.pixel(32, 32).unwrap();
        assert!(centre[0] as u32 > 2 * centre[2] as u32, "{centre:?}");
        // Outside the red quad but inside the blue one, blue shows.
        let side = img.pixel(32, 10).unwrap();
        assert!(side[2] as u32 > 2 * side[0] as u32, "{side:?}");
    }
}

#[test]
fn hair_lines_are_drawn_and_depth_tested() {
    let strands: Vec<LineItem> = (0..5)
        .map(|k| LineItem {
            points: (0..10).map(|j| [k as f32 * 0.2 - 0.4, 0.8 - j as f32 * 0.16, 0.0]).collect(),
            color: [90, 50, 20],
            width_px: 2.0,
        })
        .collect();
    let opts = plain(64, 64, Some(front_camera()));
    let mut scene = RenderScene {
        meshes: vec![],
        lines: strands,
        background: BG,
    };
    let shown = render(&scene, &opts).unwrap().non_background_fraction(BG);
    assert!(shown > 0.03, "{shown}");
    // A quad in front of the strands hides them.
    scene
        .meshes
        .push(mesh(shapes::plane_quad([0.0, 0.0, 0.5], [0.0, 0.0, 1.0], 0.4), [250, 250, 250]));
    let img = render(&scene, &opts).unwrap();
    let centre = img.pixel(32, 32).unwrap();
    assert!(luminance(centre) > 150.0, "{centre:?}");
}

#[test]
fn nan_vertices_and_empty_scenes_do_not_panic() {
    let (mut p, t) = shapes::uv_sphere([0.0; 3], 1.0, 16);
    p[3] = [f32::NAN, 0.0, 0.0];
    p[7] = [0.0, f32::INFINITY, 0.0];
    let scene = RenderScene {
        meshes: vec![
            MeshItem {
                positions: p,
                triangles: t,
                color: [200; 3],
            },
            MeshItem {
                positions: vec![[f32::NAN; 3]; 3],
                triangles: vec![[0, 1, 2]],
                color: [0; 3],
            },
        ],
        lines: vec![LineItem {
            points: vec![[0.0; 3], [f32::NAN; 3], [1.0, 1.0, 1.0], [1.0, 2.0, 1.0]],
            color: [0; 3],
            width_px: 1.5,
        }],
        background: BG,
    };
    let img = render(&scene, &RenderOptions::default()).unwrap();
    assert!(img.non_background_fraction(BG) > 0.05);
    let empty = RenderScene {
        background: [10, 20, 30],
        ..RenderScene::default()
    };
    let img = render(&empty, &RenderOptions::default()).unwrap();
    assert_eq!(img.non_background_fraction([10, 20, 30]), 0.0);
    assert_eq!(empty.bounds(), None);
}

#[test]
fn bad_options_and_items_are_errors() {
    let scene = RenderScene {
        meshes: vec![mesh(shapes::box_mesh([0.0; 3], [1.0; 3]), [100; 3])],
        ..RenderScene::default()
    };
    let ok = RenderOptions::default();
    for bad in [
        RenderOptions { width: 0, ..ok },
        RenderOptions { height: 0, ..ok },
        RenderOptions { supersample: 0, ..ok },
        RenderOptions { supersample: 9, ..ok },
        RenderOptions {
            width: 100_000,
            height: 100_000,
            ..ok
        },
    ] {
        assert!(render(&scene, &bad).is_err(), "{bad:?}");
    }
    let mut cam = front_camera();
    cam.eye = [f32::NAN; 3];
    assert!(render(&scene, &RenderOptions { camera: Some(cam), ..ok }).is_err());
    let mut bad_index = scene.clone();
    bad_index.meshes[0].triangles.push([0, 1, 99]);
    assert!(render(&bad_index, &ok).is_err());
    let mut bad_width = scene.clone();
    bad_width.lines.push(LineItem {
        points: vec![[0.0; 3], [1.0; 3]],
        color: [0; 3],
        width_px: 0.0,
    });
    assert!(render(&bad_width, &ok).is_err());
}

#[test]
fn camera_inside_the_scene_clips_instead_of_failing() {
    let scene = RenderScene {
        meshes: vec![mesh(shapes::plane_quad([0.0; 3], [0.0, 1.0, 0.0], 50.0), [120; 3])],
        lines: vec![],
        background: BG,
    };
    let cam = Camera {
        eye: [0.0, 0.5, 0.0],
        target: [0.0, 0.0, -3.0],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: 60.0,
    };
    let img = render(
        &scene,
        &RenderOptions {
            camera: Some(cam),
            ..plain(64, 48, None)
        },
    )
    .unwrap();
    dump(&img, "dbg_inside", 6);
    // The floor fills the lower part of the view and not the upper part.
    assert!(is_object(img.pixel(32, 46).unwrap()));
    assert!(!is_object(img.pixel(32, 2).unwrap()));
}

#[test]
fn shadows_darken_what_lies_under_an_occluder() {
    let floor = mesh(shapes::plane_quad([0.0; 3], [0.0, 1.0, 0.0], 3.0), [200; 3]);
    let ball = mesh(shapes::uv_sphere([0.0, 1.2, 0.0], 0.6, 32), [200; 3]);
    let scene = RenderScene {
        meshes: vec![floor, ball],
        lines: vec![],
        background: BG,
    };
    let opts = RenderOptions {
        width: 96,
        height: 72,
        ..RenderOptions::default()
    };
    let camera = Camera::framing_for_aspect([-3.0, 0.0, -3.0], [3.0, 1.8, 3.0], 96.0 / 72.0);
    let opts = RenderOptions {
        camera: Some(camera),
        ..opts
    };
    let with = render(&scene, &opts).unwrap();
    let without = render(&scene, &RenderOptions { shadows: false, ..opts }).unwrap();
    dump(&with, "dbg_with", 5);
    dump(&without, "dbg_without", 5);
    // Some pixels get clearly darker (the floor under the ball), none get brighter.
    let (mut darker, mut brighter) = (0, 0);
    for (a, b) in with.rgb.chunks(3).zip(without.rgb.chunks(3)) {
        let (la, lb) = (luminance([a[0], a[1], a[2]]), luminance([b[0], b[1], b[2]]));
        darker += usize::from(la < lb - 25.0);
        brighter += usize::from(la > lb + 1.0);
    }
    assert!(darker > 20 && brighter == 0, "darker {darker} brighter {brighter}");
}

/// Prints the time of a 512x512 render of a 100k-triangle mesh (not a timed assertion:
/// speed goals live in benches). `cargo test --lib render::tests::perf -- --ignored --nocapture`.
#[test]
#[ignore]
fn perf_100k_triangles() {
    let (p, t) = shapes::uv_sphere([0.0; 3], 1.0, 316);
    assert!(t.len() >= 99_000, "{}", t.len());
    let scene = RenderScene {
        meshes: vec![mesh((p, t), [150, 160, 170])],
        ..RenderScene::default()
    };
    let opts = RenderOptions {
        width: 512,
        height: 512,
        ..RenderOptions::default()
    };
    for (name, shadows) in [("with shadows", true), ("without shadows", false)] {
        let opts = RenderOptions {
            shadows,
            ground_shadow: shadows,
            ..opts
        };
        let start = std::time::Instant::now();
        let runs = 5;
        for _ in 0..runs {
            render(&scene, &opts).unwrap();
        }
        let ms = start.elapsed().as_secs_f64() * 1e3 / runs as f64;
        println!("512x512, supersample 2, 99k triangles, {name}: {ms:.1} ms per render");
    }
}

/// Writes `img` magnified `k` times to `/tmp/NAME.png` when WEFT_RENDER_DUMP is set (for
/// looking at test pictures by eye).
#[allow(dead_code)]
fn dump(img: &Image, name: &str, k: u32) {
    if std::env::var_os("WEFT_RENDER_DUMP").is_none() {
        return;
    }
    let mut big = Image::new(img.width * k, img.height * k, [0; 3]);
    for y in 0..big.height {
        for x in 0..big.width {
            let p = img.pixel(x / k, y / k).unwrap();
            let i = 3 * (y * big.width + x) as usize;
            big.rgb[i..i + 3].copy_from_slice(&p);
        }
    }
    big.write_png(&std::env::temp_dir().join(format!("{name}.png"))).unwrap();
}

#[test]
fn huge_finite_coordinates_give_a_picture_or_an_error_never_a_panic() {
    for big in [1e18f32, 1e30, f32::MAX] {
        let scene = RenderScene {
            meshes: vec![MeshItem {
                positions: vec![[0.0; 3], [big, 0.0, 0.0], [0.0, big, -big]],
                triangles: vec![[0, 1, 2]],
                color: [100; 3],
            }],
            lines: vec![LineItem {
                points: vec![[0.0; 3], [-big, big, big]],
                color: [0; 3],
                width_px: 3.0,
            }],
            background: BG,
        };
        let _ = render(&scene, &plain(32, 24, None));
        let _ = render(&scene, &plain(32, 24, Some(front_camera())));
    }
}

#[test]
fn supersampling_blends_edge_pixels() {
    let (positions, triangles) = shapes::plane_quad([0.0; 3], [0.0, 0.0, 1.0], 0.6);
    let tilted: Vec<[f32; 3]> = positions
        .iter()
        .map(|p| {
            let (s, c) = 0.35f32.sin_cos();
            [c * p[0] - s * p[1], s * p[0] + c * p[1], p[2]]
        })
        .collect();
    let scene = RenderScene {
        meshes: vec![MeshItem {
            positions: tilted,
            triangles,
            color: [0; 3],
        }],
        lines: vec![],
        background: [255; 3],
    };
    let mid = |ss: u32| {
        let opts = RenderOptions {
            supersample: ss,
            ..plain(48, 48, Some(front_camera()))
        };
        let img = render(&scene, &opts).unwrap();
        img.rgb
            .chunks(3)
            .filter(|p| (80.0..200.0).contains(&luminance([p[0], p[1], p[2]])))
            .count()
    };
    assert_eq!(mid(1), 0);
    assert!(mid(4) > 20, "{}", mid(4));
}
