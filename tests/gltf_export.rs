//! The glTF writer: the file parses back (container, required JSON, accessors in range), the
//! frames decode to the positions and normals written, an independent reader (the `gltf`
//! crate) accepts it, and bad input or an oversized export is an error.

mod common;

use common::glb;
use std::ops::Range;
use weft::export::{glb_bytes, GltfMesh, Topology, MAX_GLB_BYTES};

/// A 3 x 3 vertex sheet waving over `frames` frames.
fn sheet_frames(frames: usize) -> Vec<Vec<[f32; 3]>> {
    (0..frames)
        .map(|f| {
            (0..9)
                .map(|i| {
                    let (r, c) = ((i / 3) as f32, (i % 3) as f32);
                    [0.1 * c + 0.37, 1.3 - 0.05 * f as f32 * r, (0.3 * f as f32 + c).sin() * 0.1]
                })
                .collect()
        })
        .collect()
}

fn sheet_triangles() -> Vec<[u32; 3]> {
    let mut t = Vec::new();
    for r in 0..2u32 {
        for c in 0..2u32 {
            let i = r * 3 + c;
            t.push([i, i + 3, i + 1]);
            t.push([i + 1, i + 3, i + 4]);
        }
    }
    t
}

fn unit(v: [f32; 3]) -> [f32; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|c| c / l)
}

/// Decoded = base + (frame - base) in f32: equal to the frame to within rounding of the sum.
fn close(a: [f32; 3], b: [f32; 3], scale: f32) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() <= 2.0 * f32::EPSILON * scale)
}

#[test]
fn frames_round_trip_through_the_file() {
    let n = 5;
    let pos = sheet_frames(n);
    let nor: Vec<Vec<[f32; 3]>> = (0..n)
        .map(|f| (0..9).map(|i| unit([0.1 * i as f32, 1.0, 0.2 * f as f32])).collect())
        .collect();
    let tris = sheet_triangles();
    let hair: Vec<Vec<[f32; 3]>> = (0..n)
        .map(|f| (0..8).map(|i| [0.0, -0.1 * i as f32, 0.01 * (f * i) as f32]).collect())
        .collect();
    let strips: Vec<Range<u32>> = vec![0..4, 4..8];
    let ball = vec![[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]];
    let ball_t = [[0u32, 1, 2]];
    let times = [0.0f32, 0.1, 0.2, 0.35, 0.5];
    let meshes = [
        GltfMesh {
            name: "cloth",
            color: [0.5, 0.1, 0.1, 1.0],
            topology: Topology::Triangles(&tris),
            positions: pos.iter().map(|p| &p[..]).collect(),
            normals: nor.iter().map(|p| &p[..]).collect(),
        },
        GltfMesh {
            name: "hair",
            color: [0.1, 0.05, 0.0, 1.0],
            topology: Topology::LineStrips(&strips),
            positions: hair.iter().map(|p| &p[..]).collect(),
            normals: vec![],
        },
        GltfMesh {
            name: "still",
            color: [0.5, 0.5, 0.5, 1.0],
            topology: Topology::Triangles(&ball_t),
            positions: vec![&ball[..]],
            normals: vec![],
        },
    ];
    let bytes = glb_bytes(&meshes, &times).unwrap();
    let g = glb::parse(&bytes);

    let decoded = g.frames("cloth");
    assert_eq!(decoded.len(), n);
    for f in 0..n {
        for i in 0..9 {
            assert!(
                close(decoded[f][i], pos[f][i], 2.0),
                "frame {f} vertex {i}: {:?} vs {:?}",
                decoded[f][i],
                pos[f][i]
            );
        }
    }
    assert_eq!(decoded[0], pos[0], "the base frame is stored exactly");
    let normals = g.frames_of("cloth", "NORMAL");
    for f in 0..n {
        for i in 0..9 {
            assert!(close(normals[f][i], nor[f][i], 2.0));
        }
    }
    let cloth = g.primitive("cloth");
    assert_eq!(cloth["mode"], 4);
    let idx = g.u32s(cloth["indices"].as_u64().unwrap() as usize);
    assert_eq!(idx, tris.iter().flatten().copied().collect::<Vec<_>>());

    let h = g.primitive("hair");
    assert_eq!(h["mode"], 1);
    assert_eq!(
        g.u32s(h["indices"].as_u64().unwrap() as usize),
        vec![0, 1, 1, 2, 2, 3, 4, 5, 5, 6, 6, 7]
    );
    let hf = g.frames("hair");
    assert!(hf.iter().zip(&hair).all(|(a, b)| a.iter().zip(b).all(|(a, b)| close(*a, *b, 1.0))));

    let still = g.primitive("still");
    assert!(still.get("targets").is_none(), "a mesh given one frame has no morph targets");
    assert_eq!(g.frames("still"), vec![ball.clone()]);

    // One animation, one channel per moving mesh; weights one-hot per key.
    let anim = &g.json["animations"][0];
    assert_eq!(anim["channels"].as_array().unwrap().len(), 2);
    let s = &anim["samplers"][0];
    assert_eq!(s["interpolation"], "LINEAR");
    assert_eq!(g.floats(s["input"].as_u64().unwrap() as usize), times.to_vec());
    let w = g.floats(s["output"].as_u64().unwrap() as usize);
    assert_eq!(w.len(), n * (n - 1));
    for f in 0..n {
        for t in 0..n - 1 {
            assert_eq!(w[f * (n - 1) + t], if t + 1 == f { 1.0 } else { 0.0 });
        }
    }
}

#[test]
fn the_gltf_crate_reads_what_we_write() {
    let n = 4;
    let pos = sheet_frames(n);
    let tris = sheet_triangles();
    let nor: Vec<Vec<[f32; 3]>> = (0..n).map(|_| vec![[0.0, 0.0, 1.0]; 9]).collect();
    let meshes = [GltfMesh {
        name: "cloth",
        color: [0.5, 0.1, 0.1, 1.0],
        topology: Topology::Triangles(&tris),
        positions: pos.iter().map(|p| &p[..]).collect(),
        normals: nor.iter().map(|p| &p[..]).collect(),
    }];
    let bytes = glb_bytes(&meshes, &[0.0, 0.5, 1.0, 1.5]).unwrap();
    let doc = gltf::Gltf::from_slice(&bytes).expect("the gltf crate validates the file");
    let blob = doc.blob.clone().expect("binary chunk");
    let mesh = doc.meshes().next().unwrap();
    let prim = mesh.primitives().next().unwrap();
    assert_eq!(prim.mode(), gltf::mesh::Mode::Triangles);
    let reader = prim.reader(|_| Some(&blob[..]));
    let base: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
    assert_eq!(base, pos[0]);
    let targets: Vec<Vec<[f32; 3]>> = reader.read_morph_targets().map(|(p, _, _)| p.unwrap().collect()).collect();
    assert_eq!(targets.len(), n - 1);
    for (f, t) in targets.iter().enumerate() {
        for i in 0..9 {
            let got = [0, 1, 2].map(|k| base[i][k] + t[i][k]);
            assert!(close(got, pos[f + 1][i], 2.0));
        }
    }
    let anim = doc.animations().next().unwrap();
    let ch = anim.channels().next().unwrap();
    assert_eq!(ch.target().property(), gltf::animation::Property::MorphTargetWeights);
    let r = ch.reader(|_| Some(&blob[..]));
    let inputs: Vec<f32> = r.read_inputs().unwrap().collect();
    assert_eq!(inputs, vec![0.0, 0.5, 1.0, 1.5]);
    match r.read_outputs().unwrap() {
        gltf::animation::util::ReadOutputs::MorphTargetWeights(w) => assert_eq!(w.into_f32().count(), n * (n - 1)),
        _ => panic!("expected morph target weights"),
    }
}

#[test]
fn bad_input_is_an_error() {
    let pos = sheet_frames(2);
    let tris = sheet_triangles();
    fn mesh<'a>(positions: Vec<&'a [[f32; 3]]>, tris: &'a [[u32; 3]]) -> GltfMesh<'a> {
        GltfMesh {
            name: "m",
            color: [1.0; 4],
            topology: Topology::Triangles(tris),
            positions,
            normals: vec![],
        }
    }
    let tris = &tris[..];
    let ok = mesh(vec![&pos[0], &pos[1]], tris);
    assert!(glb_bytes(std::slice::from_ref(&ok), &[0.0, 1.0]).is_ok());
    // Frame times: none, not increasing, negative, NaN, or not one per frame.
    for times in [&[][..], &[1.0, 1.0], &[-1.0, 0.0], &[0.0, f32::NAN], &[0.0, 1.0, 2.0]] {
        assert!(glb_bytes(std::slice::from_ref(&ok), times).is_err(), "{times:?}");
    }
    let mut nan = pos[1].clone();
    nan[3][1] = f32::NAN;
    assert!(glb_bytes(&[mesh(vec![&pos[0], &nan], tris)], &[0.0, 1.0]).is_err());
    assert!(glb_bytes(&[mesh(vec![&pos[0], &pos[1][..5]], tris)], &[0.0, 1.0]).is_err());
    assert!(glb_bytes(&[mesh(vec![], tris)], &[0.0]).is_err());
    assert!(glb_bytes(&[mesh(vec![&pos[0]], &[[0, 1, 9]])], &[0.0]).is_err());
    let strips = [0..4, 4..10]; // the second runs past the 9 vertices
    let lines = GltfMesh {
        topology: Topology::LineStrips(&strips),
        ..mesh(vec![&pos[0]], tris)
    };
    assert!(glb_bytes(&[lines], &[0.0]).is_err());
    let dark = GltfMesh {
        color: [2.0, 0.0, 0.0, 1.0],
        ..mesh(vec![&pos[0]], tris)
    };
    assert!(glb_bytes(&[dark], &[0.0]).is_err());
}

#[test]
fn an_export_over_the_limit_is_refused_before_allocating() {
    // 1 M vertices over 50 frames is 600 MB of positions: over MAX_GLB_BYTES. Two alternating
    // frames keep the input small.
    let v = 1 << 20;
    let a = vec![[0.0f32; 3]; v];
    let b = vec![[1.0f32; 3]; v];
    let frames = 50;
    assert!(frames as u64 * v as u64 * 12 > MAX_GLB_BYTES);
    let tri = [[0u32, 1, 2]];
    let m = GltfMesh {
        name: "big",
        color: [1.0; 4],
        topology: Topology::Triangles(&tri),
        positions: (0..frames).map(|f| if f % 2 == 0 { &a[..] } else { &b[..] }).collect(),
        normals: vec![],
    };
    let times: Vec<f32> = (0..frames).map(|f| f as f32).collect();
    let e = glb_bytes(&[m], &times).unwrap_err().to_string();
    assert!(e.contains("exceeds the limit"), "{e}");
}
