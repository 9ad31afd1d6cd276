//! The public API of tissue-collide: detection by BVH vs BVH and BVH vs voxels against brute force
//! on seeded soups, the fixture meshes and the plane-press scene (also after motion and refit);
//! the edge–triangle cases; impulse conservation laws; position correction; a cloth dropped on a
//! sphere; errors.
#![allow(clippy::unwrap_used, clippy::panic)]

use glam::{Vec3, Vec3A};
use proptest::prelude::*;
use tissue_bvh::scenes::{self, jitter, to_vec3a, Rng};
use tissue_bvh::{BuildOptions, Bvh, Split};
use tissue_collide::{
    apply_impulses, detect_brute_force, detect_bvh_bvh, detect_bvh_voxels, edge_triangle, impulse,
    Bodies, BroadPhase, CollideError, Collider, ColliderOptions, Contact, ContactParams,
    DetectWorkspace, ImpulseWorkspace, ResponseParams, Side, Snapshot, Surface, VoxelGrid,
};
use tissue_mesh::{grid, uv_sphere, TriMesh};

fn fixture(name: &str) -> TriMesh {
    let path = format!("{}/../../fixtures/{name}", env!("CARGO_MANIFEST_DIR"));
    tissue_meshio::read_surface(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

fn moved(mesh: &TriMesh, by: Vec3) -> Vec<Vec3A> {
    mesh.positions()
        .iter()
        .map(|&p| Vec3A::from(p + by))
        .collect()
}

/// Count and an order-independent checksum of a contact set (every field).
fn summary(contacts: &[Contact]) -> (usize, u64) {
    let sum = contacts.iter().fold(0u64, |acc, c| {
        let mut h = (c.edge_side as u64) << 62 ^ u64::from(c.edge) << 32 ^ u64::from(c.triangle);
        for x in [c.s, c.depth, c.normal.x, c.normal.y, c.normal.z]
            .into_iter()
            .chain(c.barycentric)
        {
            h = h.wrapping_mul(0x100_0000_01B3) ^ u64::from(x.to_bits());
        }
        acc.wrapping_add(h.wrapping_mul(0x9E37_79B9_7F4A_7C15))
    });
    (contacts.len(), sum)
}

/// One pair of surfaces at given positions, checked three ways.
struct Pair {
    a: Surface,
    b: Surface,
    bvh_a: Bvh,
    bvh_b: Bvh,
    grid_b: VoxelGrid,
    ws: DetectWorkspace,
}

impl Pair {
    fn new(a: &TriMesh, pa: &[Vec3A], b: &TriMesh, pb: &[Vec3A], split: Split, cell: f32) -> Pair {
        let (a, b) = (Surface::new(a), Surface::new(b));
        let va = a.view(Side::A, pa).unwrap();
        let vb = b.view(Side::B, pb).unwrap();
        let opts = |leaf_size| BuildOptions {
            leaf_size,
            split,
            margin: 0.0,
        };
        let bvh_a = Bvh::build(va.triangles(), &opts(8)).unwrap();
        let bvh_b = Bvh::build(vb.triangles(), &opts(4)).unwrap();
        let grid_b = VoxelGrid::new(&vb, cell).unwrap();
        Pair {
            a,
            b,
            bvh_a,
            bvh_b,
            grid_b,
            ws: DetectWorkspace::new(),
        }
    }

    fn update(&mut self, pa: &[Vec3A], pb: &[Vec3A]) {
        let va = self.a.view(Side::A, pa).unwrap();
        let vb = self.b.view(Side::B, pb).unwrap();
        self.bvh_a.refit(va.triangles()).unwrap();
        self.bvh_b.refit(vb.triangles()).unwrap();
        self.grid_b.update(&vb).unwrap();
    }

    /// Asserts that the three methods agree at `params`; returns the contacts.
    fn check(
        &mut self,
        pa: &[Vec3A],
        pb: &[Vec3A],
        params: &ContactParams,
        what: &str,
    ) -> Vec<Contact> {
        let va = self.a.view(Side::A, pa).unwrap();
        let vb = self.b.view(Side::B, pb).unwrap();
        self.bvh_a.assert_well_formed(va.triangles());
        self.bvh_b.assert_well_formed(vb.triangles());
        let mut brute = Vec::new();
        detect_brute_force(&va, &vb, params, &mut brute).unwrap();
        let mut by_bvh = Vec::new();
        let stats = detect_bvh_bvh(
            &va,
            &self.bvh_a,
            &vb,
            &self.bvh_b,
            params,
            &mut self.ws,
            &mut by_bvh,
        )
        .unwrap();
        let mut by_voxels = Vec::new();
        detect_bvh_voxels(
            &va,
            &self.bvh_a,
            &vb,
            &self.grid_b,
            params,
            &mut self.ws,
            &mut by_voxels,
        )
        .unwrap();
        assert_eq!(stats.contacts as usize, by_bvh.len());
        assert_eq!(
            summary(&by_bvh),
            summary(&brute),
            "{what}: BVH vs BVH == brute force"
        );
        assert_eq!(
            summary(&by_voxels),
            summary(&brute),
            "{what}: BVH vs voxels == brute force"
        );
        assert_eq!(by_bvh, brute, "{what}");
        assert_eq!(by_voxels, brute, "{what}");
        brute
    }
}

#[test]
fn methods_agree_with_brute_force_on_random_soups_before_and_after_motion() {
    let mut total = 0;
    for seed in 0..6u64 {
        let a = scenes::triangle_soup(seed, 600, 1.0, 0.08).unwrap();
        let b = scenes::triangle_soup(seed + 50, 250, 0.7, 0.1).unwrap();
        let (mut pa, mut pb) = (to_vec3a(a.positions()), to_vec3a(b.positions()));
        let split = if seed % 2 == 0 {
            Split::EqualArea
        } else {
            Split::Sah
        };
        let cell = [0.05, 0.1, 0.3][seed as usize % 3];
        let mut pair = Pair::new(&a, &pa, &b, &pb, split, cell);
        let mut rng = Rng::new(seed);
        for round in 0..3 {
            pair.grid_b
                .assert_well_formed(&pair.b.view(Side::B, &pb).unwrap());
            for tolerance in [0.0, 0.01] {
                let params = ContactParams {
                    tolerance,
                    shared_particles: false,
                };
                let what = format!("seed {seed} round {round} tolerance {tolerance}");
                let contacts = pair.check(&pa, &pb, &params, &what);
                total += contacts.len();
            }
            jitter(&mut pa, &mut rng, 0.03);
            jitter(&mut pb, &mut rng, 0.03);
            pair.update(&pa, &pb);
        }
    }
    assert!(
        total > 1000,
        "the soups must actually collide ({total} contacts)"
    );
}

#[test]
fn methods_agree_with_brute_force_on_fixture_meshes() {
    let plane = fixture("plane_1cm_65.obj");
    let sphere = fixture("sphere_r0.25_994.obj");
    assert_eq!(
        sphere,
        uv_sphere(32, 31, 0.25).unwrap(),
        "fixture = its recipe"
    );
    let cube = fixture("cube_2cm_386.obj");
    let ball = fixture("sphere_r1_134.obj");
    let cases = [
        // The plane press: the sphere pushed 0.03 cm through the plane, off centre.
        (
            &plane,
            Vec3::ZERO,
            &sphere,
            Vec3::new(0.013, -0.007, -0.22),
            0.05,
        ),
        // The volume-preservation check: the r = 1 sphere pressed into the 2 cm cube's top.
        (&cube, Vec3::ZERO, &ball, Vec3::new(0.1, 0.05, 1.8), 0.4),
    ];
    let mut rng = Rng::new(42);
    for (i, (a, ta, b, tb, cell)) in cases.into_iter().enumerate() {
        let (mut pa, mut pb) = (moved(a, ta), moved(b, tb));
        let mut pair = Pair::new(a, &pa, b, &pb, Split::EqualArea, cell);
        for round in 0..3 {
            pair.grid_b
                .assert_well_formed(&pair.b.view(Side::B, &pb).unwrap());
            for tolerance in [0.0, 0.005] {
                let params = ContactParams {
                    tolerance,
                    shared_particles: false,
                };
                let contacts = pair.check(&pa, &pb, &params, &format!("case {i} round {round}"));
                assert!(
                    contacts.iter().any(|c| c.is_crossing()),
                    "case {i}: must intersect"
                );
                assert!(contacts.iter().any(|c| c.edge_side == Side::A));
                assert!(contacts.iter().any(|c| c.edge_side == Side::B));
            }
            jitter(&mut pa, &mut rng, 0.004);
            jitter(&mut pb, &mut rng, 0.004);
            pair.update(&pa, &pb);
        }
    }
}

#[test]
fn methods_agree_on_the_two_layer_plane_press() {
    // The 129² plane's region (both layers, ~14.7 k triangles) and the thesis's sphere, which
    // pushes 0.02 cm into layer 2; then the region sags and the sphere moves.
    let scene = scenes::plane_press(129, 0.05, 0.02).unwrap();
    let (mut pa, mut pb) = (
        to_vec3a(scene.region.positions()),
        to_vec3a(scene.sphere.positions()),
    );
    let mut pair = Pair::new(
        &scene.region,
        &pa,
        &scene.sphere,
        &pb,
        Split::EqualArea,
        0.05,
    );
    let params = ContactParams {
        tolerance: 0.001,
        shared_particles: false,
    };
    let first = pair.check(&pa, &pb, &params, "press");
    assert!(first.len() > 50, "{} contacts", first.len());
    for p in &mut pa {
        p.z -= 0.01 * (1.0 - 4.0 * (p.x * p.x + p.y * p.y)).max(0.0);
    }
    for p in &mut pb {
        *p += Vec3A::new(0.02, 0.0, 0.005);
    }
    pair.update(&pa, &pb);
    let second = pair.check(&pa, &pb, &params, "after motion");
    assert_ne!(summary(&first), summary(&second));
}

#[test]
fn contacts_are_sorted_deterministic_and_thread_count_independent() {
    let scene = scenes::plane_press(129, 0.05, 0.02).unwrap();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut c =
                Collider::new(&scene.region, &scene.sphere, &ColliderOptions::default()).unwrap();
            let pa = to_vec3a(scene.region.positions());
            let pb = to_vec3a(scene.sphere.positions());
            (c.detect(&pa, &pb).unwrap().to_vec(), c.bvh_a().clone())
        })
    };
    let (one, bvh_one) = run(1);
    let (two, bvh_two) = run(2);
    assert_eq!(bvh_one, bvh_two, "hierarchy built on 1 and 2 threads");
    assert_eq!(one, two, "contacts on 1 and 2 threads");
    assert!(one.windows(2).all(|w| w[0].key() < w[1].key()));
}

/// The 65² press scene's region and sphere under two colliders at tolerance 0.002 cm, one
/// without coherence and one with a 0.004 cm margin, and the positions (region, sphere).
fn press_colliders() -> (Collider, Collider, Vec<Vec3A>, Vec<Vec3A>) {
    let scene = scenes::plane_press(65, 0.05, 0.0).unwrap();
    let options = |coherence_margin| ColliderOptions {
        contact: ContactParams {
            tolerance: 0.002,
            shared_particles: false,
        },
        coherence_margin,
        ..ColliderOptions::default()
    };
    let full = Collider::new(&scene.region, &scene.sphere, &options(0.0)).unwrap();
    let coherent = Collider::new(&scene.region, &scene.sphere, &options(0.004)).unwrap();
    (
        full,
        coherent,
        to_vec3a(scene.region.positions()),
        to_vec3a(scene.sphere.positions()),
    )
}

#[test]
fn temporal_coherence_finds_exactly_the_full_detections_contacts() {
    // The sphere rises through the 65² press region in small steps while the region sags:
    // a collider that re-tests the pairs kept within tolerance + margin gives the contacts
    // of a full detection, bit for bit, at every step, and re-tests most steps.
    let (mut full, mut coherent, mut pa, mut pb) = press_colliders();
    let (mut retests, mut total) = (0, 0);
    for step in 0..60 {
        for p in &mut pb {
            p.z += 0.0005;
        }
        for p in &mut pa {
            p.z -= 0.0001 * (1.0 - 4.0 * (p.x * p.x + p.y * p.y)).max(0.0);
        }
        let expected = full.detect(&pa, &pb).unwrap().to_vec();
        let got = coherent.detect(&pa, &pb).unwrap().to_vec();
        assert_eq!(got, expected, "step {step}");
        total += expected.len();
        if coherent.stats().triangle_pairs == 0 {
            retests += 1;
        }
    }
    assert!(total > 1000, "{total} contacts in all");
    assert!(retests > 40, "{retests} of 60 steps re-tested");
}

#[test]
fn coherence_drops_the_margin_while_the_motion_outruns_it() {
    // The sphere jumps 0.01 cm per step (2.5 margins) for 10 steps, each detection called
    // twice at the same positions (a step's detection and the next one's, after an unchanged
    // separation), then creeps 0.0005 cm per step. Every call gives a full detection's contacts
    // bit for bit; while jumping, each detection is a plain one at the tolerance (its counts
    // are the full collider's: no margin pairs kept); creeping, most steps are re-tests.
    let (mut full, mut coherent, pa, mut pb) = press_colliders();
    let (mut plain, mut retests, mut total) = (0, 0, 0);
    for step in 0..50 {
        let rise = if step < 10 { 0.01 } else { 0.0005 };
        for p in &mut pb {
            p.z += rise;
        }
        for call in 0..2 {
            let expected = full.detect(&pa, &pb).unwrap().to_vec();
            let got = coherent.detect(&pa, &pb).unwrap().to_vec();
            assert_eq!(got, expected, "step {step}, call {call}");
            total += expected.len();
        }
        let (c, f) = (coherent.stats(), full.stats());
        if step > 0 && step < 10 && c.triangle_pairs > 0 && c == f {
            plain += 1;
        }
        if step >= 10 && c.triangle_pairs == 0 {
            retests += 1;
        }
    }
    assert!(total > 1000, "{total} contacts in all");
    assert_eq!(plain, 9, "jumping steps detected at the bare tolerance");
    assert!(retests > 30, "{retests} of 40 creeping steps re-tested");
}

// --- Edge–triangle cases ---------------------------------------------------------------------

fn unit_triangle() -> [Vec3A; 3] {
    [Vec3A::ZERO, Vec3A::X, Vec3A::Y]
}

#[test]
fn edge_crossing_the_triangle() {
    let [a, b, c] = unit_triangle();
    let (p, q) = (Vec3A::new(0.2, 0.3, 0.1), Vec3A::new(0.2, 0.3, -0.3));
    let hit = edge_triangle(p, q, a, b, c, 0.0).unwrap();
    assert!((hit.s - 0.25).abs() < 1e-6);
    assert!((hit.barycentric[1] - 0.2).abs() < 1e-6 && (hit.barycentric[2] - 0.3).abs() < 1e-6);
    // p is nearer the plane (0.1 above): the edge moves down, by 0.1, to clear it.
    assert_eq!(hit.normal, -Vec3A::Z);
    assert!((hit.depth - 0.1).abs() < 1e-6);
    // Reversed edge: same point, s mirrored.
    let rev = edge_triangle(q, p, a, b, c, 0.0).unwrap();
    assert!((rev.s - 0.75).abs() < 1e-6);
    assert_eq!(rev.normal, -Vec3A::Z);
}

#[test]
fn edge_touching_at_a_vertex() {
    let [a, b, c] = unit_triangle();
    // The edge's endpoint on the triangle's interior, the rest above: touching, depth 0.
    let hit = edge_triangle(
        Vec3A::new(0.2, 0.2, 0.0),
        Vec3A::new(0.3, 0.2, 0.5),
        a,
        b,
        c,
        0.0,
    )
    .unwrap();
    assert_eq!((hit.s, hit.depth), (0.0, 0.0));
    assert!((hit.barycentric[1] - 0.2).abs() < 1e-6 && (hit.barycentric[2] - 0.2).abs() < 1e-6);
    assert_eq!(hit.normal, Vec3A::Z);
    // The edge's endpoint on the triangle's vertex b (a different particle at the same place).
    let hit = edge_triangle(b, Vec3A::new(1.5, 0.5, 0.5), a, b, c, 0.0).unwrap();
    assert_eq!(hit.depth, 0.0);
    assert!((hit.barycentric[1] - 1.0).abs() < 1e-6);
    // The same endpoint a hair above: no contact at tolerance 0, a near contact within 1e-3.
    let p = b + Vec3A::new(0.0, 0.0, 1e-4);
    assert!(edge_triangle(p, Vec3A::new(1.5, 0.5, 0.5), a, b, c, 0.0).is_none());
    let near = edge_triangle(p, Vec3A::new(1.5, 0.5, 0.5), a, b, c, 1e-3).unwrap();
    assert!((near.depth + 1e-4).abs() < 1e-7);
}

#[test]
fn edge_lying_in_the_plane() {
    let [a, b, c] = unit_triangle();
    // Across the triangle, in its plane: touching (distance 0), never "crossing".
    let hit = edge_triangle(
        Vec3A::new(-0.5, 0.25, 0.0),
        Vec3A::new(1.5, 0.25, 0.0),
        a,
        b,
        c,
        0.0,
    )
    .unwrap();
    assert_eq!(hit.depth, 0.0);
    assert_eq!(hit.normal, Vec3A::Z);
    // Wholly inside the triangle, in its plane.
    let hit = edge_triangle(
        Vec3A::new(0.1, 0.1, 0.0),
        Vec3A::new(0.3, 0.2, 0.0),
        a,
        b,
        c,
        0.0,
    )
    .unwrap();
    assert_eq!(hit.depth, 0.0);
    // In the plane but beside the triangle.
    assert!(edge_triangle(
        Vec3A::new(2.0, 0.0, 0.0),
        Vec3A::new(2.0, 1.0, 0.0),
        a,
        b,
        c,
        0.0
    )
    .is_none());
}

#[test]
fn edge_parallel_offset() {
    let [a, b, c] = unit_triangle();
    let (p, q) = (Vec3A::new(0.1, 0.1, 0.05), Vec3A::new(0.6, 0.1, 0.05));
    assert!(edge_triangle(p, q, a, b, c, 0.0).is_none());
    assert!(edge_triangle(p, q, a, b, c, 0.049).is_none());
    let near = edge_triangle(p, q, a, b, c, 0.06).unwrap();
    assert!((near.depth + 0.05).abs() < 1e-6);
    assert!((near.normal - Vec3A::Z).length() < 1e-6);
    // Below: the normal points down, toward the edge.
    let (p2, q2) = (Vec3A::new(0.1, 0.1, -0.05), Vec3A::new(0.6, 0.1, -0.05));
    assert!((edge_triangle(p2, q2, a, b, c, 0.06).unwrap().normal + Vec3A::Z).length() < 1e-6);
}

#[test]
fn edge_sharing_a_vertex_is_no_contact() {
    // Two triangles of one particle array: [0, 1, 2] (surface A) and [1, 3, 4] (surface B) share
    // particle 1. B's edge 1–3 touches A's triangle at particle 1, and A's edges touch B's
    // triangle there: geometrically touching, topologically neighbours.
    let positions = vec![
        Vec3::ZERO,
        Vec3::X,
        Vec3::Y,
        Vec3::new(1.5, 0.5, 0.5),
        Vec3::new(1.5, -0.5, 0.5),
    ];
    let a = TriMesh::new(positions.clone(), vec![[0, 1, 2]]).unwrap();
    let b = TriMesh::new(positions.clone(), vec![[1, 3, 4]]).unwrap();
    let pos = to_vec3a(&positions);
    let (sa, sb) = (Surface::new(&a), Surface::new(&b));
    let (va, vb) = (
        sa.view(Side::A, &pos).unwrap(),
        sb.view(Side::B, &pos).unwrap(),
    );
    let mut out = Vec::new();
    let shared = ContactParams {
        tolerance: 0.0,
        shared_particles: true,
    };
    detect_brute_force(&va, &vb, &shared, &mut out).unwrap();
    assert!(out.is_empty(), "{out:?}");
    // The same geometry as separate particle sets: they do touch at that point.
    let separate = ContactParams {
        shared_particles: false,
        ..shared
    };
    detect_brute_force(&va, &vb, &separate, &mut out).unwrap();
    assert!(!out.is_empty());
    assert!(out.iter().all(|c| c.depth == 0.0));
}

#[test]
fn edge_through_the_common_side_of_two_triangles_is_found() {
    // A square of two triangles; edges through the diagonal and through the shared vertex.
    let square = grid(2, 1.0).unwrap();
    let pos = to_vec3a(square.positions());
    let line = TriMesh::new(
        vec![
            Vec3::new(0.1, 0.1, 0.3),
            Vec3::new(0.1, 0.1, -0.3),
            Vec3::new(0.3, 0.3, 0.0),
            Vec3::new(0.5, 0.5, 0.2),
            Vec3::new(0.5, 0.5, -0.2),
            Vec3::new(0.6, 0.5, 0.0),
        ],
        vec![[0, 1, 2], [3, 4, 5]],
    )
    .unwrap();
    let lpos = to_vec3a(line.positions());
    let (sa, sb) = (Surface::new(&square), Surface::new(&line));
    let mut out = Vec::new();
    detect_brute_force(
        &sa.view(Side::A, &pos).unwrap(),
        &sb.view(Side::B, &lpos).unwrap(),
        &ContactParams::default(),
        &mut out,
    )
    .unwrap();
    let crossing: Vec<_> = out
        .iter()
        .filter(|c| c.edge_side == Side::B && c.is_crossing())
        .collect();
    // The diagonal of grid(2) at (0,0)-(0.5,0.5) corner: each vertical edge crosses at least one
    // of the two triangles (both when on their common side).
    for e in [0u32, 1] {
        let edge = sb
            .edges()
            .iter()
            .position(|&x| x == [3 * e, 3 * e + 1])
            .unwrap() as u32;
        assert!(crossing.iter().any(|c| c.edge == edge), "edge {e}: {out:?}");
    }
    assert!(out.iter().all(|c| c.normal.is_finite() && c.s.is_finite()));
}

#[test]
fn degenerate_triangle_is_handled() {
    let (a, b, c) = (Vec3A::ZERO, Vec3A::X, Vec3A::new(2.0, 0.0, 0.0));
    let hit = edge_triangle(
        Vec3A::new(0.5, -0.5, 0.0),
        Vec3A::new(0.5, 0.5, 0.0),
        a,
        b,
        c,
        0.0,
    )
    .unwrap();
    assert_eq!(hit.depth, 0.0);
    assert!(hit.normal.is_finite() && hit.normal.length() > 0.99);
    assert!(edge_triangle(
        Vec3A::new(0.5, -0.5, 1.0),
        Vec3A::new(0.5, 0.5, 1.0),
        a,
        b,
        c,
        0.0
    )
    .is_none());
}

// --- Impulses ---------------------------------------------------------------------------------

mod strategies {
    use super::*;

    pub fn vec3(r: f32) -> impl Strategy<Value = Vec3A> {
        (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| Vec3A::new(x, y, z))
    }

    /// Five velocities, five positive inverse masses, `s` and barycentric coordinates, a unit
    /// normal, restitution and friction.
    #[allow(clippy::type_complexity)]
    pub fn contact() -> impl Strategy<Value = ([Vec3A; 5], [f32; 5], f32, [f32; 3], Vec3A, f32, f32)>
    {
        (
            prop::array::uniform5(vec3(100.0)),
            prop::array::uniform5(0.05f32..20.0),
            0.0f32..=1.0,
            (0.0f32..1.0, 0.0f32..1.0),
            vec3(1.0).prop_filter("non-zero normal", |n| n.length() > 0.1),
            0.0f32..=1.0,
            0.0f32..2.0,
        )
            .prop_map(|(v, w, s, (u, t), n, e, mu)| {
                let (u, t) = if u + t > 1.0 {
                    (1.0 - u, 1.0 - t)
                } else {
                    (u, t)
                };
                (v, w, s, [1.0 - u - t, u, t], n.normalize(), e, mu)
            })
    }
}

fn weights(s: f32, bary: [f32; 3]) -> [f32; 5] {
    [1.0 - s, s, -bary[0], -bary[1], -bary[2]]
}

fn relative(v: &[Vec3A; 5], w: &[f32; 5]) -> Vec3A {
    (0..5).map(|k| v[k] * w[k]).sum()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(500))]

    #[test]
    fn impulse_conserves_momentum_and_reverses_normal_velocity(
        (v, inv_m, s, bary, n, e, mu) in strategies::contact()
    ) {
        let c = weights(s, bary);
        let before = relative(&v, &c).dot(n);
        match impulse(v, inv_m, c, n, e, mu) {
            None => prop_assert!(before >= 0.0),
            Some(imp) => {
                prop_assert!(before < 0.0);
                let after: [Vec3A; 5] = [0, 1, 2, 3, 4].map(|k| v[k] + imp.dv[k]);
                // Momentum: Σ m Δv = 0 to float precision.
                let p: Vec3A = (0..5).map(|k| imp.dv[k] / inv_m[k]).sum();
                let scale: f32 = (0..5).map(|k| imp.dv[k].length() / inv_m[k]).sum();
                prop_assert!(p.length() <= 1e-5 * scale.max(1e-6), "Σ m Δv = {p} (scale {scale})");
                // Normal: v_n after = −e · v_n before.
                let vn_after = relative(&after, &c).dot(n);
                prop_assert!((vn_after + e * before).abs() <= 1e-4 * before.abs().max(1.0),
                    "after {vn_after}, before {before}, e {e}");
                // Coulomb: the friction impulse is at most μ·j and never reverses the sliding.
                prop_assert!(imp.friction <= mu * imp.normal * (1.0 + 1e-5) + 1e-6);
                let vt = |x: &[Vec3A; 5]| { let r = relative(x, &c); r - n * r.dot(n) };
                prop_assert!(vt(&after).length() <= vt(&v).length() * (1.0 + 1e-4) + 1e-4);
            }
        }
    }
}

#[test]
fn fixed_particles_take_no_impulse() {
    let v = [
        Vec3A::new(0.0, 0.0, -1.0),
        Vec3A::new(0.0, 0.0, -1.0),
        Vec3A::ZERO,
        Vec3A::ZERO,
        Vec3A::ZERO,
    ];
    let w = [1.0, 1.0, 0.0, 0.0, 0.0];
    let imp = impulse(v, w, weights(0.5, [0.2, 0.3, 0.5]), Vec3A::Z, 0.5, 0.0).unwrap();
    assert!(imp.dv[2..].iter().all(|&d| d == Vec3A::ZERO));
    // A fixed triangle: the edge point's normal velocity is reversed and halved (e = 0.5).
    let after = v[0] + imp.dv[0];
    assert!((after.z - 0.5).abs() < 1e-6, "{after}");
    // All fixed: nothing to do.
    assert!(impulse(
        v,
        [0.0; 5],
        weights(0.5, [0.2, 0.3, 0.5]),
        Vec3A::Z,
        0.5,
        0.0
    )
    .is_none());
}

#[test]
fn eq_8_two_point_masses() {
    // s = 0 and barycentric (1, 0, 0): particle 0 against particle 2 — the thesis's two-body
    // impulse j = −(1+e)(v₂−v₁)·n / (1/m₁ + 1/m₂).
    let (m1, m2, e) = (2.0f32, 3.0f32, 0.3f32);
    let v = [
        Vec3A::new(0.0, 0.0, -4.0),
        Vec3A::ZERO,
        Vec3A::new(0.0, 0.0, 1.0),
        Vec3A::ZERO,
        Vec3A::ZERO,
    ];
    let w = [1.0 / m1, 7.0, 1.0 / m2, 7.0, 7.0];
    let imp = impulse(v, w, weights(0.0, [1.0, 0.0, 0.0]), Vec3A::Z, e, 0.0).unwrap();
    let j = -(1.0 + e) * (-4.0 - 1.0) / (1.0 / m1 + 1.0 / m2);
    assert!((imp.normal - j).abs() < 1e-4);
    assert!((imp.dv[0].z - j / m1).abs() < 1e-5 && (imp.dv[2].z + j / m2).abs() < 1e-5);
    assert_eq!(
        (imp.dv[1], imp.dv[3], imp.dv[4]),
        (Vec3A::ZERO, Vec3A::ZERO, Vec3A::ZERO)
    );
}

#[test]
fn apply_impulses_conserves_momentum_over_many_contacts() {
    // The plane press with both bodies free: all contacts, several sweeps.
    let scene = scenes::plane_press(65, 0.05, 0.03).unwrap();
    let (pa, pb) = (
        to_vec3a(scene.region.positions()),
        to_vec3a(scene.sphere.positions()),
    );
    let mut c = Collider::new(&scene.region, &scene.sphere, &ColliderOptions::default()).unwrap();
    let n = c.detect(&pa, &pb).unwrap().len();
    assert!(n > 20);
    let mut rng = Rng::new(3);
    let inv_a: Vec<f32> = pa.iter().map(|_| rng.range(0.5, 2.0)).collect();
    let inv_b: Vec<f32> = pb.iter().map(|_| rng.range(0.5, 2.0)).collect();
    let mut va = vec![Vec3A::new(0.0, 0.0, -3.0); pa.len()];
    let mut vb = vec![Vec3A::new(0.5, 0.0, 5.0); pb.len()];
    let momentum = |va: &[Vec3A], vb: &[Vec3A]| -> glam::DVec3 {
        va.iter()
            .zip(&inv_a)
            .chain(vb.iter().zip(&inv_b))
            .map(|(v, w)| (*v / *w).as_dvec3())
            .sum()
    };
    let before = momentum(&va, &vb);
    let params = ResponseParams {
        restitution: 0.2,
        friction: 0.3,
        ..ResponseParams::default()
    };
    let report = c
        .apply_impulses(&mut Bodies::two(&mut va, &inv_a, &mut vb, &inv_b), &params)
        .unwrap();
    assert!(report.active > 0);
    let after = momentum(&va, &vb);
    assert!(
        (after - before).length() < 1e-4 * before.length(),
        "{before} -> {after}"
    );
    // With one set of particles shared by both surfaces, the same holds (Bodies::One).
    let mut all = va.clone();
    all.extend_from_slice(&vb);
    let mut inv_all = inv_a.clone();
    inv_all.extend_from_slice(&inv_b);
    let shift = pa.len() as u32;
    let shifted: Vec<Contact> = c
        .contacts()
        .iter()
        .map(|c| {
            let mut c = *c;
            if c.edge_side == Side::B {
                c.edge_particles = c.edge_particles.map(|i| i + shift);
            } else {
                c.triangle_particles = c.triangle_particles.map(|i| i + shift);
            }
            c
        })
        .collect();
    let total = |v: &[Vec3A]| -> glam::DVec3 {
        v.iter()
            .zip(&inv_all)
            .map(|(v, w)| (*v / *w).as_dvec3())
            .sum()
    };
    let before = total(&all);
    apply_impulses(
        &shifted,
        &mut Bodies::one(&mut all, &inv_all),
        &params,
        &mut ImpulseWorkspace::new(),
    )
    .unwrap();
    assert!((total(&all) - before).length() < 1e-4 * before.length());
}

#[test]
fn warm_start_conserves_momentum_and_holds_a_steadily_loaded_contact_with_one_sweep() {
    // The plane press region resting on the sphere, pressed down by a steady load each step
    // (the velocity gravity would add): with one sweep per step, a cold start leaves the
    // contacts approaching (the shared particles' impulses fight each other), while warm
    // starting from the last step's impulses converges over the steps to a resting contact.
    let scene = scenes::plane_press(65, 0.05, 0.03).unwrap();
    let (pa, pb) = (
        to_vec3a(scene.region.positions()),
        to_vec3a(scene.sphere.positions()),
    );
    let inv_a: Vec<f32> = vec![1.0; pa.len()];
    let inv_b: Vec<f32> = vec![0.0; pb.len()];
    let run = |warm_start: f32| -> (f64, f64) {
        let mut c =
            Collider::new(&scene.region, &scene.sphere, &ColliderOptions::default()).unwrap();
        let params = ResponseParams {
            sweeps: 1,
            warm_start,
            ..ResponseParams::default()
        };
        let contacts = c.detect(&pa, &pb).unwrap().to_vec();
        assert!(contacts.len() > 20);
        let mut va = vec![Vec3A::ZERO; pa.len()];
        let mut vb = vec![Vec3A::ZERO; pb.len()];
        let mut worst = 0.0f64;
        let mut downward_push = 0.0f64;
        for _ in 0..30 {
            // A steady load on the region's particles; the velocities are not integrated, so
            // every step sees the same contacts and the same load.
            va.iter_mut().for_each(|v| *v = Vec3A::new(0.0, 0.0, -1.0));
            let before: glam::DVec3 = va.iter().map(|v| v.as_dvec3()).sum();
            let report = c
                .apply_impulses(&mut Bodies::two(&mut va, &inv_a, &mut vb, &inv_b), &params)
                .unwrap();
            // The sphere is fixed, so momentum is not conserved here; but the impulses only
            // push the region away from the sphere below it: its total z velocity never falls.
            let after: glam::DVec3 = va.iter().map(|v| v.as_dvec3()).sum();
            downward_push = downward_push.max((after.z - before.z).min(0.0).abs());
            assert!(report.normal_impulse.is_finite());
            worst = contacts
                .iter()
                .map(|k| {
                    let v = (1.0 - k.s) * va[k.edge_particles[0] as usize]
                        + k.s * va[k.edge_particles[1] as usize];
                    f64::from(v.dot(Vec3A::from(k.normal)).min(0.0).abs())
                })
                .fold(0.0, f64::max);
        }
        (worst, downward_push)
    };
    let (cold, _) = run(0.0);
    let (warm, downward_push) = run(1.0);
    assert!(downward_push < 1e-6, "{downward_push}");
    assert!(cold > 0.05, "cold start, one sweep: approach {cold}");
    assert!(warm < 0.2 * cold, "warm {warm} vs cold {cold}");

    // With two free bodies, warm-started impulses conserve momentum.
    let mut c = Collider::new(&scene.region, &scene.sphere, &ColliderOptions::default()).unwrap();
    c.detect(&pa, &pb).unwrap();
    let mut rng = Rng::new(5);
    let inv_a: Vec<f32> = pa.iter().map(|_| rng.range(0.5, 2.0)).collect();
    let inv_b: Vec<f32> = pb.iter().map(|_| rng.range(0.5, 2.0)).collect();
    let params = ResponseParams {
        friction: 0.3,
        warm_start: 1.0,
        ..ResponseParams::default()
    };
    let momentum = |va: &[Vec3A], vb: &[Vec3A]| -> glam::DVec3 {
        va.iter()
            .zip(&inv_a)
            .chain(vb.iter().zip(&inv_b))
            .map(|(v, w)| (*v / *w).as_dvec3())
            .sum()
    };
    for _ in 0..3 {
        let mut va = vec![Vec3A::new(0.0, 0.0, -3.0); pa.len()];
        let mut vb = vec![Vec3A::new(0.5, 0.0, 5.0); pb.len()];
        let before = momentum(&va, &vb);
        c.apply_impulses(&mut Bodies::two(&mut va, &inv_a, &mut vb, &inv_b), &params)
            .unwrap();
        let after = momentum(&va, &vb);
        assert!((after - before).length() < 1e-4 * before.length());
    }
    let bad = ResponseParams {
        warm_start: 1.5,
        ..ResponseParams::default()
    };
    assert!(bad.validate().is_err());
}

// --- Position correction and the drop test ------------------------------------------------------

/// Generalised winding number of a closed mesh around `p` (≈ 1 inside, ≈ 0 outside).
fn winding_number(mesh: &TriMesh, positions: &[Vec3A], p: Vec3A) -> f32 {
    let mut sum = 0.0f64;
    for t in mesh.triangles() {
        let [a, b, c] = t.map(|i| (positions[i as usize] - p).as_dvec3());
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let num = a.dot(b.cross(c));
        let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
        sum += 2.0 * num.atan2(den);
    }
    (sum / (4.0 * std::f64::consts::PI)) as f32
}

#[test]
fn separate_leaves_no_edge_through_a_triangle_in_the_plane_press() {
    // Layer 2 of the region free, the sphere free and moving up into it for a few steps.
    let scene = scenes::plane_press(65, 0.05, -0.004).unwrap();
    let mut pa = to_vec3a(scene.region.positions());
    let mut pb = to_vec3a(scene.sphere.positions());
    let inv_a = vec![1.0; pa.len()];
    let inv_b = vec![0.5; pb.len()];
    let mut c = Collider::new(&scene.region, &scene.sphere, &ColliderOptions::default()).unwrap();
    let params = ResponseParams::default();
    for _ in 0..4 {
        let (prev_a, prev_b) = (pa.clone(), pb.clone());
        for p in &mut pb {
            p.z += 0.003;
        }
        let report = c
            .separate(
                &mut Bodies::two(&mut pa, &inv_a, &mut pb, &inv_b),
                Some(Snapshot {
                    a: &prev_a,
                    b: &prev_b,
                }),
                &params,
            )
            .unwrap();
        assert_eq!(report.remaining, 0, "{report:?}");
        let mut all = Vec::new();
        let (sa, sb) = (Surface::new(&scene.region), Surface::new(&scene.sphere));
        detect_brute_force(
            &sa.view(Side::A, &pa).unwrap(),
            &sb.view(Side::B, &pb).unwrap(),
            &ContactParams::default(),
            &mut all,
        )
        .unwrap();
        assert!(
            all.iter().all(|c| !c.is_crossing()),
            "brute force still finds a crossing"
        );
    }
}

#[test]
fn cloth_dropped_on_a_fixed_sphere_stays_outside() {
    // A 0.36 cm cloth patch of 17 × 17 particles (no springs: each particle falls on its own; the
    // patch's edges and triangles are what collides) thrown down at 50 cm/s from 0.1 cm above the
    // fixed r = 0.25 cm sphere of the plane press, under gravity. Step 1 ms: a particle moves up
    // to 0.05 cm per step, twice the patch's 0.0225 cm spacing and about the sphere's triangle
    // size, so most contacts are found as crossings after the move and must be undone.
    let sphere = fixture("sphere_r0.25_994.obj");
    let cloth_mesh = grid(17, 0.36).unwrap();
    let mut x = moved(&cloth_mesh, Vec3::new(0.01, -0.02, 0.35));
    let mut v = vec![Vec3A::new(0.0, 0.0, -50.0); x.len()];
    let inv_cloth = vec![1.0 / 0.01; x.len()];
    let mut xs = to_vec3a(sphere.positions());
    let mut vs = vec![Vec3A::ZERO; xs.len()];
    let inv_sphere = vec![0.0; xs.len()];
    let options = ColliderOptions {
        contact: ContactParams {
            tolerance: 0.002,
            shared_particles: false,
        },
        ..ColliderOptions::default()
    };
    let mut c = Collider::new(&cloth_mesh, &sphere, &options).unwrap();
    let params = ResponseParams {
        restitution: 0.0,
        friction: 0.5,
        ..ResponseParams::default()
    };
    let (h, g) = (1e-3f32, Vec3A::new(0.0, 0.0, -981.0));
    let middle = 8 * 17 + 8;
    let (mut most_contacts, mut corrected, mut landed) = (0, 0, false);
    for step in 0..150 {
        // (1)-(2) forces and velocities.
        for vi in &mut v {
            *vi += g * h;
        }
        // (3) collisions.
        c.detect(&x, &xs).unwrap();
        most_contacts = most_contacts.max(c.contacts().len());
        c.apply_impulses(
            &mut Bodies::two(&mut v, &inv_cloth, &mut vs, &inv_sphere),
            &params,
        )
        .unwrap();
        // (4) positions, then no edge left through a triangle.
        let (prev, prev_s) = (x.clone(), xs.clone());
        for (xi, vi) in x.iter_mut().zip(&v) {
            *xi += *vi * h;
        }
        let report = c
            .separate(
                &mut Bodies::two(&mut x, &inv_cloth, &mut xs, &inv_sphere),
                Some(Snapshot {
                    a: &prev,
                    b: &prev_s,
                }),
                &params,
            )
            .unwrap();
        assert_eq!(report.remaining, 0, "step {step}: {report:?}");
        corrected += report.corrected;
        landed |= (x[middle].length() - 0.25).abs() < 0.005 && v[middle].length() < 5.0;
        if step % 10 == 9 {
            for (i, &p) in x.iter().enumerate() {
                let w = winding_number(&sphere, &xs, p);
                assert!(
                    w < 0.5,
                    "step {step}: cloth particle {i} at {p} is inside (winding {w})"
                );
            }
        }
    }
    assert_eq!(xs, to_vec3a(sphere.positions()), "the sphere is fixed");
    assert_eq!(vs, vec![Vec3A::ZERO; xs.len()], "the sphere is fixed");
    assert!(
        landed,
        "the middle of the patch must come to rest on the sphere's top"
    );
    assert!(
        most_contacts > 100 && corrected > 100,
        "{most_contacts} contacts, {corrected} corrections"
    );
}

// --- Errors ----------------------------------------------------------------------------------

#[test]
fn errors_name_what_is_wrong() {
    let plane = grid(5, 1.0).unwrap();
    let sphere = uv_sphere(8, 7, 0.2).unwrap();
    let (pa, pb) = (to_vec3a(plane.positions()), to_vec3a(sphere.positions()));
    let (sa, sb) = (Surface::new(&plane), Surface::new(&sphere));
    assert!(matches!(
        sa.view(Side::A, &pa[..3]),
        Err(CollideError::ParticleCount {
            side: Side::A,
            expected: 25,
            got: 3,
            ..
        })
    ));
    let (va, vb) = (
        sa.view(Side::A, &pa).unwrap(),
        sb.view(Side::B, &pb).unwrap(),
    );
    let mut out = Vec::new();
    assert!(matches!(
        detect_brute_force(&vb, &va, &ContactParams::default(), &mut out),
        Err(CollideError::WrongSide {
            expected: Side::A,
            got: Side::B
        })
    ));
    let bad = ContactParams {
        tolerance: -1.0,
        shared_particles: false,
    };
    assert!(matches!(
        detect_brute_force(&va, &vb, &bad, &mut out),
        Err(CollideError::InvalidParameter {
            name: "tolerance",
            ..
        })
    ));
    let bvh_b = Bvh::build(vb.triangles(), &BuildOptions::default()).unwrap();
    assert!(matches!(
        detect_bvh_bvh(
            &va,
            &bvh_b,
            &vb,
            &bvh_b,
            &ContactParams::default(),
            &mut DetectWorkspace::new(),
            &mut out
        ),
        Err(CollideError::TriangleCount { side: Side::A, .. })
    ));
    assert!(matches!(
        VoxelGrid::new(&vb, 0.0),
        Err(CollideError::InvalidParameter {
            name: "cell_size",
            ..
        })
    ));
    assert!(matches!(
        VoxelGrid::new(&vb, 1e-5),
        Err(CollideError::TooManyCells { .. })
    ));
    let mut nan = pb.clone();
    nan[7].y = f32::NAN;
    assert!(matches!(
        VoxelGrid::new(&sb.view(Side::B, &nan).unwrap(), 0.1),
        Err(CollideError::NonFinitePosition {
            side: Side::B,
            particle: 7,
            ..
        })
    ));
    let mut c = Collider::new(&plane, &sphere, &ColliderOptions::default()).unwrap();
    assert!(matches!(
        c.detect(&pa, &nan),
        Err(CollideError::Bvh { side: Side::B, .. })
    ));
    let bad_e = ResponseParams {
        restitution: 1.5,
        ..ResponseParams::default()
    };
    let (mut v1, mut v2) = (vec![Vec3A::ZERO; 25], vec![Vec3A::ZERO; pb.len()]);
    let (w1, w2) = (vec![1.0; 25], vec![1.0; pb.len()]);
    assert!(matches!(
        c.apply_impulses(&mut Bodies::two(&mut v1, &w1, &mut v2, &w2), &bad_e),
        Err(CollideError::InvalidParameter {
            name: "restitution",
            ..
        })
    ));
    // A contact naming a particle the arrays do not have; a negative inverse mass.
    let contact = Contact {
        edge_side: Side::A,
        edge: 0,
        edge_particles: [0, 99],
        s: 0.5,
        triangle: 0,
        triangle_particles: [0, 1, 2],
        barycentric: [0.2, 0.3, 0.5],
        normal: Vec3::Z,
        depth: 0.1,
    };
    let p = ResponseParams::default();
    assert!(matches!(
        apply_impulses(
            &[contact],
            &mut Bodies::two(&mut v1, &w1, &mut v2, &w2),
            &p,
            &mut ImpulseWorkspace::new()
        ),
        Err(CollideError::ParticleOutOfRange {
            side: Side::A,
            particle: 99,
            count: 25
        })
    ));
    let mut w_bad = w1.clone();
    w_bad[0] = -1.0;
    let ok_contact = Contact {
        edge_particles: [0, 1],
        ..contact
    };
    assert!(matches!(
        apply_impulses(
            &[ok_contact],
            &mut Bodies::two(&mut v1, &w_bad, &mut v2, &w2),
            &p,
            &mut ImpulseWorkspace::new()
        ),
        Err(CollideError::InvalidInverseMass {
            side: Side::A,
            particle: 0,
            ..
        })
    ));
    let msg = CollideError::InvalidInverseMass {
        side: Side::A,
        particle: 0,
        value: -1.0,
    }
    .to_string();
    assert!(msg.contains("particle 0") && msg.contains("fixed"), "{msg}");
}

#[test]
fn collider_with_voxels_matches_collider_with_bvh() {
    let scene = scenes::plane_press(65, 0.05, 0.02).unwrap();
    let (pa, mut pb) = (
        to_vec3a(scene.region.positions()),
        to_vec3a(scene.sphere.positions()),
    );
    let mut bvh = Collider::new(&scene.region, &scene.sphere, &ColliderOptions::default()).unwrap();
    let mut vox = Collider::new(
        &scene.region,
        &scene.sphere,
        &ColliderOptions {
            broad_phase: BroadPhase::BvhVoxels,
            ..ColliderOptions::default()
        },
    )
    .unwrap();
    let sb = Surface::new(&scene.sphere);
    for step in 0..5 {
        let x = bvh.detect(&pa, &pb).unwrap().to_vec();
        let y = vox.detect(&pa, &pb).unwrap().to_vec();
        assert_eq!(x, y, "step {step}");
        assert!(!x.is_empty());
        vox.voxels_b()
            .unwrap()
            .assert_well_formed(&sb.view(Side::B, &pb).unwrap());
        for p in &mut pb {
            *p += Vec3A::new(0.003, 0.001, 0.002);
        }
    }
}
