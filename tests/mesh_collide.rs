//! Mesh-obstacle collision invariants (after Landovskaya, Landovsky & Frolovsky): every broadphase gives the same
//! contacts bit for bit, crossing segments never tunnel, degenerate positions give no NaN,
//! and the parallel batch equals the serial one for any thread count.

use proptest::prelude::*;
use weft::obstacles::mesh::batch::{contacts_par, contacts_serial, contacts_with_memory_par, contacts_with_memory_serial, Soa3};
use weft::obstacles::mesh::broadphase::bvh::Bvh;
use weft::obstacles::mesh::broadphase::grid::UniformGrid;
use weft::obstacles::mesh::broadphase::hash::{mean_face_size, FaceHash};
use weft::obstacles::mesh::broadphase::{BruteForce, FaceBroadphase};
use weft::obstacles::mesh::dressform::dress_form;
use weft::obstacles::mesh::narrow::{mesh_contact_with, Contact, ContactKind};
use weft::obstacles::mesh::TriMesh;

/// UV sphere of radius ~1 with radial bumps `amp * bumps[k]`, star-shaped about the origin.
fn bumpy_sphere(seg: usize, rings: usize, amp: f32, bumps: &[f32]) -> TriMesh {
    let mut v = vec![[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]];
    for i in 1..rings {
        let phi = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..seg {
            let th = std::f32::consts::TAU * j as f32 / seg as f32;
            let r = 1.0 + amp * bumps[(i * seg + j) % bumps.len()];
            v.push([r * phi.sin() * th.cos(), -r * phi.cos(), r * phi.sin() * th.sin()]);
        }
    }
    let id = |i: usize, j: usize| (2 + (i - 1) * seg + j % seg) as u32;
    let mut f = Vec::new();
    for j in 0..seg {
        f.push([0, id(1, j), id(1, j + 1)]);
        f.push([1, id(rings - 1, j + 1), id(rings - 1, j)]);
    }
    for i in 1..rings - 1 {
        for j in 0..seg {
            f.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
            f.push([id(i, j + 1), id(i + 1, j), id(i + 1, j + 1)]);
        }
    }
    let (m, r) = TriMesh::new(v, f).unwrap();
    assert_eq!(r.boundary_edges + r.non_manifold_edges + r.misoriented_edges, 0);
    assert_eq!(m.solid_side(), Some(1.0), "outward winding");
    m
}

/// A box of half-sizes `h` centred at the origin (12 large faces).
fn cuboid(h: [f32; 3]) -> TriMesh {
    let v: Vec<[f32; 3]> = (0..8)
        .map(|i| [0, 1, 2].map(|k| if i >> k & 1 == 1 { h[k] } else { -h[k] }))
        .collect();
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let f = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
    TriMesh::new(v, f).unwrap().0
}

/// A contact as raw bits, for exact comparison.
type Bits = (u32, [u32; 3], [u32; 3], u32, u32, ContactKind);

fn bits(c: &Option<Contact>) -> Option<Bits> {
    c.map(|c| {
        (
            c.face,
            c.point.map(f32::to_bits),
            c.normal.map(f32::to_bits),
            c.t.to_bits(),
            c.depth.to_bits(),
            c.kind,
        )
    })
}

fn broadphases(m: &TriMesh) -> Vec<Box<dyn FaceBroadphase + Sync>> {
    let s = mean_face_size(m);
    vec![
        Box::new(UniformGrid::new(m, [1, 1, 1]).unwrap()),
        Box::new(UniformGrid::new(m, [5, 5, 5]).unwrap()),
        Box::new(UniformGrid::new(m, [15, 30, 15]).unwrap()),
        Box::new(UniformGrid::new(m, [2, 9, 4]).unwrap()),
        Box::new(UniformGrid::auto(m).unwrap()),
        Box::new(Bvh::new(m)),
        Box::new(FaceHash::new(m, s).unwrap()),
        Box::new(FaceHash::new(m, 0.25 * s).unwrap()),
        Box::new(FaceHash::new(m, 4.0 * s).unwrap()),
    ]
}

fn mesh_strategy() -> impl Strategy<Value = TriMesh> {
    prop_oneof![
        (4usize..20, 3usize..14, 0.0f32..0.3, prop::collection::vec(-1.0f32..1.0, 1..50))
            .prop_map(|(s, r, a, b)| bumpy_sphere(s, r, a, &b)),
        (0.05f32..2.0, 0.05f32..2.0, 0.05f32..2.0).prop_map(|(a, b, c)| cuboid([a, b, c])),
        (16usize..3000).prop_map(|t| dress_form(t).unwrap()),
    ]
}

/// A segment start and end in and around the mesh box, from short to fast (box-crossing).
fn segment(m: &TriMesh, u: [f32; 6], scale: f32) -> ([f32; 3], [f32; 3]) {
    let (lo, hi) = m.bounds();
    let x = [0, 1, 2].map(|k| lo[k] + (hi[k] - lo[k]) * (1.4 * u[k] - 0.2));
    let p = [0, 1, 2].map(|k| x[k] + (hi[k] - lo[k]) * scale * (u[k + 3] - 0.5));
    (x, p)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn all_broadphases_give_identical_contacts(
        m in mesh_strategy(),
        segs in prop::collection::vec((prop::array::uniform6(0.0f32..1.0), prop_oneof![Just(0.02f32), Just(0.2), Just(2.0)]), 40),
        th in prop_oneof![Just(0.0f32), 0.0f32..0.05],
        shift in prop::array::uniform3(-5.0f32..5.0),
    ) {
        let mut m = m;
        m.translate(shift).unwrap();
        let brute = BruteForce::new(&m);
        let bps = broadphases(&m);
        let mut scratch = Vec::new();
        for (u, scale) in segs {
            let (x, p) = segment(&m, u, scale);
            let want = mesh_contact_with(&m, &brute, x, p, th, &mut scratch);
            for bp in &bps {
                let got = mesh_contact_with(&m, bp.as_ref(), x, p, th, &mut scratch);
                prop_assert_eq!(bits(&got), bits(&want), "{}", bp.describe());
            }
        }
    }

    #[test]
    fn crossing_segments_never_tunnel(
        m in mesh_strategy(),
        dirs in prop::collection::vec((prop::array::uniform3(-1.0f32..1.0), 0.1f32..0.9, any::<bool>()), 30),
    ) {
        // A far point is outside; a point on the vertical axis near the middle is inside
        // every test mesh. A straight path between them crosses the surface.
        prop_assert_eq!(m.solid_side(), Some(1.0));
        let mut sheet = m.clone();
        sheet.set_two_sided();
        let (lo, hi) = m.bounds();
        let c = [0.0, 0.5 * (lo[1] + hi[1]), 0.0];
        let far = 3.0 * (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f32::max);
        let bps = broadphases(&m);
        let mut scratch = Vec::new();
        for (d, frac, outward) in dirs {
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            prop_assume!(l > 1e-3);
            let out = [0, 1, 2].map(|k| c[k] + far * d[k] / l);
            let inside = [c[0], c[1] + (frac - 0.5) * 0.1 * (hi[1] - lo[1]), c[2]];
            let (x, p) = if outward { (inside, out) } else { (out, inside) };
            for bp in &bps {
                // two-sided: caught in both directions
                let hit = mesh_contact_with(&sheet, bp.as_ref(), x, p, 0.0, &mut scratch);
                prop_assert!(hit.is_some(), "{}: {x:?} -> {p:?} tunnelled", bp.describe());
                let hit = hit.unwrap();
                prop_assert_eq!(hit.kind, ContactKind::Crossing);
                prop_assert!(hit.t >= 0.0 && hit.t <= 1.0);
                // solid: caught going in, let out going out
                let hit = mesh_contact_with(&m, bp.as_ref(), x, p, 0.0, &mut scratch);
                prop_assert_eq!(hit.is_some(), !outward, "{}: {:?}", bp.describe(), hit);
            }
        }
    }

    #[test]
    fn exact_vertices_edges_faces_give_finite_contacts(
        m in mesh_strategy(),
        picks in prop::collection::vec((any::<prop::sample::Index>(), 0u8..3, prop::array::uniform3(-1.0f32..1.0)), 30),
        th in 0.0f32..0.02,
    ) {
        let bp = Bvh::new(&m);
        let mut scratch = Vec::new();
        for (fi, kind, d) in picks {
            let f = fi.index(m.face_count()) as u32;
            let [a, b, c] = m.corners(f);
            let q = match kind {
                0 => a,
                1 => [0, 1, 2].map(|k| 0.5 * a[k] + 0.5 * b[k]),
                _ => [0, 1, 2].map(|k| (a[k] + b[k] + c[k]) / 3.0),
            };
            let moved = [0, 1, 2].map(|k| q[k] + 0.05 * d[k]);
            for (x, p) in [(q, q), (q, moved), (moved, q)] {
                if let Some(h) = mesh_contact_with(&m, &bp, x, p, th, &mut scratch) {
                    let all = h.point.iter().chain(&h.normal).chain([&h.t, &h.depth]);
                    prop_assert!(all.copied().all(f32::is_finite), "{h:?}");
                }
            }
            if th > 0.0 {
                // standing on the surface is always within the thickness
                prop_assert!(mesh_contact_with(&m, &bp, q, q, th, &mut scratch).is_some(), "f {f} kind {kind} q {q:?} corners {:?} n {:?}", m.corners(f), m.normals()[f as usize]);
            }
        }
    }
}

fn particles(m: &TriMesh, n: usize) -> [Vec<f32>; 6] {
    let (lo, hi) = m.bounds();
    let mut s = 12345u32;
    let mut rnd = || {
        s = s.wrapping_mul(1664525).wrapping_add(1013904223);
        (s >> 8) as f32 / (1u32 << 24) as f32
    };
    let mut out: [Vec<f32>; 6] = Default::default();
    for _ in 0..n {
        for k in 0..3 {
            let x = lo[k] + (hi[k] - lo[k]) * (1.2 * rnd() - 0.1);
            out[k].push(x);
            out[k + 3].push(x + 0.05 * (rnd() - 0.5));
        }
    }
    out
}

#[test]
fn batch_parallel_equals_serial_for_1_and_2_threads() {
    let m = dress_form(2000).unwrap();
    let g = UniformGrid::auto(&m).unwrap();
    let [x, y, z, px, py, pz] = particles(&m, 3000);
    let (s, p) = (Soa3 { x: &x, y: &y, z: &z }, Soa3 { x: &px, y: &py, z: &pz });
    let mut serial = Vec::new();
    contacts_serial(&m, &g, s, p, 0.01, &mut serial).unwrap();
    assert!(serial.iter().filter(|c| c.is_some()).count() > 50);
    let mut mem_serial = vec![u32::MAX; x.len()];
    let mut out_mem_serial = Vec::new();
    for _ in 0..2 {
        contacts_with_memory_serial(&m, &g, s, p, 0.01, 0.02, &mut mem_serial, &mut out_mem_serial).unwrap();
    }
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let mut par = Vec::new();
        let mut mem = vec![u32::MAX; x.len()];
        let mut out_mem = Vec::new();
        pool.install(|| {
            contacts_par(&m, &g, s, p, 0.01, &mut par).unwrap();
            for _ in 0..2 {
                contacts_with_memory_par(&m, &g, s, p, 0.01, 0.02, &mut mem, &mut out_mem).unwrap();
            }
        });
        assert_eq!(
            par.iter().map(bits).collect::<Vec<_>>(),
            serial.iter().map(bits).collect::<Vec<_>>()
        );
        assert_eq!(
            out_mem.iter().map(bits).collect::<Vec<_>>(),
            out_mem_serial.iter().map(bits).collect::<Vec<_>>()
        );
        assert_eq!(mem, mem_serial);
    }
}

#[test]
fn batch_rejects_bad_input() {
    let mut m = dress_form(600).unwrap();
    let g = Bvh::new(&m);
    let (x, mut y, z) = (vec![0.0f32; 4], vec![0.0f32; 4], vec![0.0f32; 3]);
    let mut out = Vec::new();
    let ok = Soa3 { x: &x, y: &x, z: &x };
    assert!(contacts_par(&m, &g, ok, Soa3 { x: &x, y: &y, z: &z }, 0.01, &mut out).is_err());
    y[2] = f32::NAN;
    assert!(contacts_par(&m, &g, ok, Soa3 { x: &x, y: &y, z: &x }, 0.01, &mut out).is_err());
    assert!(contacts_serial(&m, &g, ok, ok, -1.0, &mut out).is_err());
    assert!(contacts_with_memory_par(&m, &g, ok, ok, 0.01, 0.02, &mut [0; 3], &mut out).is_err());
    contacts_par(&m, &g, ok, ok, 0.01, &mut out).unwrap();
    m.translate([0.0, 1.0, 0.0]).unwrap();
    let e = contacts_par(&m, &g, ok, ok, 0.01, &mut out).unwrap_err();
    assert!(e.to_string().contains("rebuild"), "{e}");
}

/// Is `q` inside the closed mesh `m`? Majority of the crossing parities along three oblique
/// rays (a ray grazing an edge may count the edge's two faces).
/// `m` must be two-sided here, so that leaving crossings count too.
fn inside_mesh(m: &TriMesh, q: [f32; 3]) -> bool {
    assert!(m.solid_side().is_none());
    let dirs = [[3.1271, 10.0, 1.7313], [-2.913, -7.77, 4.05], [9.1, 0.71, -3.3]];
    let votes = dirs
        .iter()
        .filter(|d| {
            let far = [q[0] + d[0], q[1] + d[1], q[2] + d[2]];
            let n = (0..m.face_count() as u32)
                .filter_map(|f| weft::obstacles::mesh::narrow::face_contact(m, f, q, far, 0.0))
                .filter(|c| c.kind == ContactKind::Crossing)
                .count();
            n % 2 == 1
        })
        .count();
    votes >= 2
}

#[test]
fn falling_particles_never_penetrate_the_form() {
    use weft::obstacles::mesh::face_memory::{project_if_remembered, Projection};
    use weft::obstacles::mesh::response::{resolve_position, resolve_velocity};
    let m = dress_form(1200).unwrap();
    let bp = UniformGrid::auto(&m).unwrap();
    let (th, band, h, mu) = (0.003f32, 0.006f32, 1.0f32 / 240.0, 0.3f32);
    let mut xs: Vec<[f32; 3]> = Vec::new();
    for i in 0..20 {
        for j in 0..20 {
            let (u, v) = (i as f32 / 19.0 - 0.5, j as f32 / 19.0 - 0.5);
            xs.push([0.36 * u, 0.85 + 0.01 * ((i + j) % 3) as f32, 0.2 * v]);
        }
    }
    let n = xs.len();
    let mut vs = vec![[0.0f32; 3]; n];
    let mut mem = vec![u32::MAX; n];
    let mut out = Vec::new();
    let mut contacts = 0;
    for _step in 0..240 {
        let mut ps = xs.clone();
        for i in 0..n {
            let g = project_if_remembered(&m, mem[i], xs[i], band, Projection::IntoFaceOnly, [0.0, -9.81, 0.0]);
            for k in 0..3 {
                vs[i][k] += h * g[k];
                ps[i][k] = xs[i][k] + h * vs[i][k];
            }
        }
        let col = |a: &Vec<[f32; 3]>, k: usize| a.iter().map(|q| q[k]).collect::<Vec<f32>>();
        let (sx, sy, sz) = (col(&xs, 0), col(&xs, 1), col(&xs, 2));
        let (qx, qy, qz) = (col(&ps, 0), col(&ps, 1), col(&ps, 2));
        let (s, p) = (Soa3 { x: &sx, y: &sy, z: &sz }, Soa3 { x: &qx, y: &qy, z: &qz });
        contacts_with_memory_serial(&m, &bp, s, p, th, band, &mut mem, &mut out).unwrap();
        for i in 0..n {
            if let Some(c) = out[i] {
                contacts += 1;
                ps[i] = resolve_position(xs[i], ps[i], &c, th);
                vs[i] = resolve_velocity(vs[i], c.normal, mu);
            }
            assert!(ps[i].iter().all(|v| v.is_finite()));
        }
        xs = ps;
    }
    assert!(contacts > n, "the particles must land on the form ({contacts} contacts)");
    let mut sheet = m.clone();
    sheet.set_two_sided();
    let inside: Vec<usize> = (0..n).filter(|&i| inside_mesh(&sheet, xs[i])).collect();
    assert!(
        inside.is_empty(),
        "{} particles inside, e.g. {:?}",
        inside.len(),
        inside.first().map(|&i| xs[i])
    );
}

#[test]
fn face_memory_batches_agree_across_broadphases() {
    let m = dress_form(3000).unwrap();
    let [x, y, z, px, py, pz] = particles(&m, 2000);
    let (s, p) = (Soa3 { x: &x, y: &y, z: &z }, Soa3 { x: &px, y: &py, z: &pz });
    let mut reference: Option<(Vec<Option<Bits>>, Vec<u32>)> = None;
    for bp in broadphases(&m) {
        let mut mem = vec![u32::MAX; x.len()];
        let mut out = Vec::new();
        let mut used = Vec::new();
        for _pass in 0..3 {
            contacts_with_memory_par(&m, bp.as_ref(), s, p, 0.01, 0.02, &mut mem, &mut out).unwrap();
            used.extend(out.iter().map(bits));
        }
        assert!(mem.iter().any(|&f| f != u32::MAX));
        match &reference {
            None => reference = Some((used, mem)),
            Some((u, mm)) => {
                assert!(u == &used && mm == &mem, "{} differs", bp.describe());
            }
        }
    }
}
