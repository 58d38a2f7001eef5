//! The table of Landovskaya, Landovsky & Frolovsky as a micro-benchmark: one contact query per cloth
//! particle against a dress form, for each broadphase. The paper's runs: 32500 particles
//! against 4800 faces with grids 1x1x1, 5x5x5, 15x30x15, and 15000 particles against 8350
//! faces with 1x1x1 and 25x25x25. Particles sit near the surface (as cloth draped on a form):
//! a random surface point lifted by -1..3 thicknesses, moving 0..5 mm in a random direction.
//! Serial queries, so the time per particle compares broadphases, not threads.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;
use weft::obstacles::mesh::batch::{contacts_par, contacts_serial, contacts_with_memory_serial, Soa3};
use weft::obstacles::mesh::broadphase::bvh::Bvh;
use weft::obstacles::mesh::broadphase::grid::UniformGrid;
use weft::obstacles::mesh::broadphase::hash::FaceHash;
use weft::obstacles::mesh::broadphase::FaceBroadphase;
use weft::obstacles::mesh::dressform::{dress_form, PRESET_4800, PRESET_8350};
use weft::obstacles::mesh::TriMesh;

const THICKNESS: f32 = 0.003;

fn draped(m: &TriMesh, n: usize) -> [Vec<f32>; 6] {
    let mut s = 0x9e37_79b9u32;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        (s >> 8) as f32 / (1u32 << 24) as f32
    };
    let mut out: [Vec<f32>; 6] = Default::default();
    for _ in 0..n {
        let f = ((rnd() * m.face_count() as f32) as u32).min(m.face_count() as u32 - 1);
        let [a, b, c] = m.corners(f);
        let (mut u, mut v) = (rnd(), rnd());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let lift = THICKNESS * (4.0 * rnd() - 1.0);
        let nrm = m.normals()[f as usize];
        let step = 0.005 * rnd();
        let d = [rnd() - 0.5, rnd() - 0.5, rnd() - 0.5];
        let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().max(1e-6);
        for k in 0..3 {
            let x = a[k] + u * (b[k] - a[k]) + v * (c[k] - a[k]) + lift * nrm[k];
            out[k].push(x);
            out[k + 3].push(x + step * d[k] / l);
        }
    }
    out
}

/// Times every broadphase of `bps`, then face memory and the parallel batch on `bps[best]`.
fn run(c: &mut Criterion, name: &str, m: &TriMesh, n: usize, bps: Vec<Box<dyn FaceBroadphase + Sync>>, best: usize) {
    let [x, y, z, px, py, pz] = draped(m, n);
    let (s, p) = (Soa3 { x: &x, y: &y, z: &z }, Soa3 { x: &px, y: &py, z: &pz });
    let mut g = c.benchmark_group(name);
    g.sample_size(10);
    g.throughput(Throughput::Elements(n as u64));
    let mut out = Vec::new();
    for bp in &bps {
        contacts_serial(m, bp.as_ref(), s, p, THICKNESS, &mut out).unwrap();
        let hits = out.iter().filter(|c| c.is_some()).count();
        eprintln!("{name} {}: {hits} of {n} particles in contact", bp.describe());
        g.bench_function(bp.describe(), |b| {
            b.iter(|| contacts_serial(m, bp.as_ref(), s, p, THICKNESS, black_box(&mut out)).unwrap())
        });
    }
    // The paper's face memory on the finest grid: memory filled by one pass, then each
    // timed pass tests only the remembered face for particles still over it.
    let bp = &bps[best];
    let mut mem = vec![u32::MAX; n];
    contacts_with_memory_serial(m, bp.as_ref(), s, p, THICKNESS, 2.0 * THICKNESS, &mut mem, &mut out).unwrap();
    let remembered = mem.iter().filter(|&&f| f != u32::MAX).count();
    eprintln!("{name} {} + face memory: {remembered} particles remember a face", bp.describe());
    g.bench_function(format!("{} + face memory", bp.describe()), |b| {
        b.iter(|| contacts_with_memory_serial(m, bp.as_ref(), s, p, THICKNESS, 2.0 * THICKNESS, &mut mem, black_box(&mut out)).unwrap())
    });
    g.bench_function(format!("{} parallel", bp.describe()), |b| {
        b.iter(|| contacts_par(m, bp.as_ref(), s, p, THICKNESS, black_box(&mut out)).unwrap())
    });
    g.finish();
}

fn table(c: &mut Criterion) {
    let m = dress_form(PRESET_4800).unwrap();
    let bps: Vec<Box<dyn FaceBroadphase + Sync>> = vec![
        Box::new(UniformGrid::new(&m, [1, 1, 1]).unwrap()),
        Box::new(UniformGrid::new(&m, [5, 5, 5]).unwrap()),
        Box::new(UniformGrid::new(&m, [15, 30, 15]).unwrap()),
        Box::new(UniformGrid::auto(&m).unwrap()),
        Box::new(Bvh::new(&m)),
        Box::new(FaceHash::auto(&m).unwrap()),
    ];
    run(c, "form4800_32500", &m, 32500, bps, 2);
    let m = dress_form(PRESET_8350).unwrap();
    let bps: Vec<Box<dyn FaceBroadphase + Sync>> = vec![
        Box::new(UniformGrid::new(&m, [1, 1, 1]).unwrap()),
        Box::new(UniformGrid::new(&m, [25, 25, 25]).unwrap()),
        Box::new(Bvh::new(&m)),
        Box::new(FaceHash::auto(&m).unwrap()),
    ];
    run(c, "form8352_15000", &m, 15000, bps, 1);
}

criterion_group!(benches, table);
criterion_main!(benches);
