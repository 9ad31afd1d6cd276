//! The public API of tissue-bvh against brute force on seeded scenes and the fixture meshes: build
//! and refit invariants, the equal-area split, pairs between hierarchies, box / point / ray
//! queries, errors.
#![allow(clippy::unwrap_used)]

use glam::{Vec3, Vec3A};
use proptest::prelude::*;
use tissue_bvh::scenes::{self, jitter, to_vec3a, Rng};
use tissue_bvh::{
    Aabb, BuildOptions, Bvh, BvhError, BvhWorkspace, Primitives, Ray, Split, Triangles,
};
use tissue_mesh::{grid, subdivided_cube, uv_sphere, TriMesh};

/// The fixture meshes (`fixtures/README.md`: each file is exactly this generator call).
fn fixture_meshes() -> Vec<(&'static str, TriMesh)> {
    vec![
        ("plane_1cm_65", grid(65, 1.0).unwrap()),
        ("sphere_r0.25_994", uv_sphere(32, 31, 0.25).unwrap()),
        ("cube_2cm_386", subdivided_cube(8, 2.0).unwrap()),
        ("sphere_r1_134", uv_sphere(12, 11, 1.0).unwrap()),
    ]
}

fn options(leaf_size: u32, split: Split) -> BuildOptions {
    BuildOptions {
        leaf_size,
        split,
        margin: 0.0,
    }
}

/// Every primitive pair `[a, b]` whose boxes overlap (with `gap`), by the hierarchies.
fn bvh_pairs<P: Primitives + ?Sized>(
    ba: &Bvh,
    pa: &P,
    bb: &Bvh,
    pb: &P,
    gap: f32,
    ws: &mut BvhWorkspace,
) -> Vec<[u32; 2]> {
    let mut leaves = Vec::new();
    ba.leaf_pairs(bb, gap, ws, &mut leaves);
    let mut out = Vec::new();
    for [la, lb] in leaves {
        for &a in ba.leaf_primitives(la) {
            for &b in bb.leaf_primitives(lb) {
                if pa.bounds(a).overlaps(&pb.bounds(b), gap) {
                    out.push([a, b]);
                }
            }
        }
    }
    out
}

fn brute_pairs<P: Primitives + ?Sized>(pa: &P, pb: &P, gap: f32) -> Vec<[u32; 2]> {
    let mut out = Vec::new();
    for a in 0..pa.primitive_count() as u32 {
        let ab = pa.bounds(a);
        for b in 0..pb.primitive_count() as u32 {
            if ab.overlaps(&pb.bounds(b), gap) {
                out.push([a, b]);
            }
        }
    }
    out
}

/// Count and an order-independent checksum of a pair set.
fn summary(pairs: &[[u32; 2]]) -> (usize, u64) {
    let sum = pairs.iter().fold(0u64, |s, &[a, b]| {
        let h = (u64::from(a) << 32 | u64::from(b)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        s.wrapping_add(h ^ (h >> 29))
    });
    (pairs.len(), sum)
}

fn assert_same_pairs(mut got: Vec<[u32; 2]>, mut want: Vec<[u32; 2]>, what: &str) {
    assert_eq!(summary(&got), summary(&want), "{what}: count and checksum");
    got.sort_unstable();
    want.sort_unstable();
    assert_eq!(got, want, "{what}");
}

#[test]
fn builds_are_well_formed_on_fixtures_for_both_splits_and_many_leaf_sizes() {
    for (name, mesh) in fixture_meshes() {
        let pos = to_vec3a(mesh.positions());
        let tris = Triangles::from_mesh(&mesh, &pos).unwrap();
        for split in [Split::EqualArea, Split::Sah] {
            for leaf_size in [1, 2, 3, 8, 31, 1000] {
                let bvh = Bvh::build(&tris, &options(leaf_size, split)).unwrap();
                bvh.assert_well_formed(&tris);
                assert_eq!(bvh.primitive_count(), mesh.triangle_count(), "{name}");
                assert_eq!(bvh.node_count(), 2 * bvh.leaf_count() - 1, "{name}");
                let root = bvh.root_aabb();
                let mb = mesh.bounding_box();
                assert_eq!((root.min, root.max), (mb.min, mb.max), "{name}");
            }
        }
    }
}

#[test]
fn equal_area_children_differ_by_at_most_one_triangle() {
    for (name, mesh) in fixture_meshes() {
        let pos = to_vec3a(mesh.positions());
        let tris = Triangles::from_mesh(&mesh, &pos).unwrap();
        let bvh = Bvh::build(&tris, &options(4, Split::EqualArea)).unwrap();
        // Summed area and the largest triangle under every node.
        let n = bvh.node_count();
        let mut area = vec![0.0f64; n];
        let mut largest = vec![0.0f64; n];
        for i in (0..n).rev() {
            let node = bvh.nodes()[i];
            if node.is_leaf() {
                for &p in bvh.leaf_primitives(i as u32) {
                    let w = f64::from(tris.weight(p));
                    area[i] += w;
                    largest[i] = largest[i].max(w);
                }
            } else {
                let c = node.first as usize;
                area[i] = area[c] + area[c + 1];
                largest[i] = largest[c].max(largest[c + 1]);
                // The cut is the weighted median: moving it by one triangle cannot help, so the
                // halves differ by at most the largest triangle under the node.
                let diff = (area[c] - area[c + 1]).abs();
                assert!(
                    diff <= largest[i] * (1.0 + 1e-5),
                    "{name}: node {i} children areas {} and {} (largest triangle {})",
                    area[c],
                    area[c + 1],
                    largest[i]
                );
            }
        }
    }
}

#[test]
fn builds_are_deterministic() {
    let mesh = scenes::triangle_soup(7, 3000, 2.0, 0.05).unwrap();
    let pos = to_vec3a(mesh.positions());
    let tris = Triangles::from_mesh(&mesh, &pos).unwrap();
    for split in [Split::EqualArea, Split::Sah] {
        let a = Bvh::build(&tris, &options(6, split)).unwrap();
        let b = Bvh::build(&tris, &options(6, split)).unwrap();
        assert_eq!(a, b);
        let mut c = a.clone();
        c.rebuild(&tris, &mut Default::default()).unwrap();
        assert_eq!(a, c);
    }
}

/// The thesis's hierarchy (SPEC A.3): 116984-triangle region, 7503 nodes, 64/128/256 nodes on
/// levels 7/8/9 (levels counted from 1 at the root).
#[test]
fn thesis_region_node_counts() {
    let scene = scenes::plane_press(257, 0.05, 0.0).unwrap();
    let mesh = &scene.region;
    assert!(
        (116_000..118_000).contains(&mesh.triangle_count()),
        "{}",
        mesh.triangle_count()
    );
    let pos = to_vec3a(mesh.positions());
    let tris = Triangles::from_mesh(mesh, &pos).unwrap();
    for (leaf_size, nodes) in [(16u32, 16383usize), (31, 8191), (32, 8191), (58, 4095)] {
        let bvh = Bvh::build(&tris, &options(leaf_size, Split::EqualArea)).unwrap();
        bvh.assert_well_formed(&tris);
        assert_eq!(bvh.node_count(), nodes, "leaf size {leaf_size}");
        let levels = bvh.level_counts();
        assert_eq!(&levels[6..9], &[64, 128, 256], "leaf size {leaf_size}");
    }
}

#[test]
fn parallel_and_serial_builds_and_refits_are_identical() {
    let scene = scenes::plane_press(257, 0.05, 0.0).unwrap();
    let mesh = &scene.region;
    let p0 = to_vec3a(mesh.positions());
    let mut p1 = p0.clone();
    jitter(&mut p1, &mut Rng::new(4), 1e-3);
    let run = |threads: usize, split: Split| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let t0 = Triangles::from_mesh(mesh, &p0).unwrap();
            let t1 = Triangles::from_mesh(mesh, &p1).unwrap();
            let mut bvh = Bvh::build(&t0, &options(8, split)).unwrap();
            let built = bvh.clone();
            let report = bvh.refit(&t1).unwrap();
            bvh.assert_well_formed(&t1);
            (built, bvh, report)
        })
    };
    for split in [Split::EqualArea, Split::Sah] {
        let serial = run(1, split);
        let parallel = run(2, split);
        assert_eq!(serial.0, parallel.0, "{split:?}: build");
        assert_eq!(serial.1, parallel.1, "{split:?}: refit");
        assert_eq!(serial.2, parallel.2, "{split:?}: refit report");
        assert_eq!(serial.2.leaves_changed as usize, serial.1.leaf_count());
    }
}

#[test]
fn pairs_match_brute_force_on_random_soups_before_and_after_refit() {
    let mut ws = BvhWorkspace::new();
    for seed in 0..6u64 {
        let a = scenes::triangle_soup(seed, 1500, 1.0, 0.04).unwrap();
        let b = scenes::triangle_soup(seed + 100, 700, 0.8, 0.06).unwrap();
        let mut pa = to_vec3a(a.positions());
        let mut pb = to_vec3a(b.positions());
        let split = if seed % 2 == 0 {
            Split::EqualArea
        } else {
            Split::Sah
        };
        let mut ba =
            Bvh::build(&Triangles::from_mesh(&a, &pa).unwrap(), &options(4, split)).unwrap();
        let mut bb =
            Bvh::build(&Triangles::from_mesh(&b, &pb).unwrap(), &options(3, split)).unwrap();
        let mut rng = Rng::new(seed);
        for round in 0..4 {
            let ta = Triangles::from_mesh(&a, &pa).unwrap();
            let tb = Triangles::from_mesh(&b, &pb).unwrap();
            ba.assert_well_formed(&ta);
            bb.assert_well_formed(&tb);
            for gap in [0.0, 0.01] {
                let got = bvh_pairs(&ba, &ta, &bb, &tb, gap, &mut ws);
                let want = brute_pairs(&ta, &tb, gap);
                assert!(!want.is_empty());
                assert_same_pairs(got, want, &format!("seed {seed} round {round} gap {gap}"));
            }
            jitter(&mut pa, &mut rng, 0.02);
            jitter(&mut pb, &mut rng, 0.02);
            ba.refit(&Triangles::from_mesh(&a, &pa).unwrap()).unwrap();
            bb.refit(&Triangles::from_mesh(&b, &pb).unwrap()).unwrap();
        }
    }
}

#[test]
fn pairs_match_brute_force_on_fixture_plane_and_sphere() {
    let plane = grid(65, 1.0).unwrap();
    let sphere = uv_sphere(32, 31, 0.25).unwrap();
    let pp = to_vec3a(plane.positions());
    let mut ps = to_vec3a(sphere.positions());
    for p in &mut ps {
        p.z += 0.2; // the sphere pushes through the plane
    }
    let tp = Triangles::from_mesh(&plane, &pp).unwrap();
    let ts = Triangles::from_mesh(&sphere, &ps).unwrap();
    let bp = Bvh::build(&tp, &options(8, Split::EqualArea)).unwrap();
    let bs = Bvh::build(&ts, &options(4, Split::EqualArea)).unwrap();
    let mut ws = BvhWorkspace::new();
    let got = bvh_pairs(&bp, &tp, &bs, &ts, 0.0, &mut ws);
    let want = brute_pairs(&tp, &ts, 0.0);
    assert!(want.len() > 100);
    assert_same_pairs(got, want, "plane vs sphere");
}

#[test]
fn refit_follows_the_thesis_semantics() {
    let mesh = grid(65, 1.0).unwrap();
    let mut pos = to_vec3a(mesh.positions());
    let mut bvh = Bvh::build(
        &Triangles::from_mesh(&mesh, &pos).unwrap(),
        &options(8, Split::EqualArea),
    )
    .unwrap();
    // Nothing moved: nothing changes.
    let report = bvh
        .refit(&Triangles::from_mesh(&mesh, &pos).unwrap())
        .unwrap();
    assert_eq!((report.nodes_changed, report.leaves_changed), (0, 0));
    assert!((report.cost - bvh.build_cost()).abs() <= 1e-4 * bvh.build_cost());

    // One interior vertex lifted: exactly the leaves holding its triangles change, and the inner
    // nodes that change lie on their paths to the root.
    let v = 32 * 65 + 32;
    pos[v].z += 0.01;
    let tris = Triangles::from_mesh(&mesh, &pos).unwrap();
    let before = bvh.clone();
    let report = bvh.refit(&tris).unwrap();
    bvh.assert_well_formed(&tris);
    let touched: Vec<u32> = mesh.topology().vertex_triangles(v as u32).to_vec();
    let leaves_with: Vec<usize> = (0..bvh.node_count())
        .filter(|&i| {
            bvh.leaf_primitives(i as u32)
                .iter()
                .any(|p| touched.contains(p))
        })
        .collect();
    assert_eq!(report.leaves_changed as usize, leaves_with.len());
    let mut on_paths = vec![false; bvh.node_count()];
    for &leaf in &leaves_with {
        on_paths[leaf] = true;
    }
    for i in (0..bvh.node_count()).rev() {
        let n = bvh.nodes()[i];
        if !n.is_leaf() && (on_paths[n.first as usize] || on_paths[n.first as usize + 1]) {
            on_paths[i] = true;
        }
    }
    let changed: Vec<usize> = (0..bvh.node_count())
        .filter(|&i| bvh.nodes()[i] != before.nodes()[i])
        .collect();
    assert_eq!(changed.len(), report.nodes_changed as usize);
    assert!(changed.iter().all(|&i| on_paths[i]));
    assert!(changed.contains(&0), "the root grows in z");
    // Leaves hold exactly their triangles' boxes (tight, no margin).
    for i in 0..bvh.node_count() as u32 {
        if bvh.nodes()[i as usize].is_leaf() {
            let tight = bvh
                .leaf_primitives(i)
                .iter()
                .fold(Aabb::EMPTY, |b, &p| b.union(&tris.bounds(p)));
            assert_eq!(bvh.nodes()[i as usize].aabb, tight);
        }
    }
}

#[test]
fn refit_cost_grows_when_the_mesh_is_scrambled_and_rebuild_restores_it() {
    let mesh = grid(65, 1.0).unwrap();
    let mut pos = to_vec3a(mesh.positions());
    let mut bvh = Bvh::build(
        &Triangles::from_mesh(&mesh, &pos).unwrap(),
        &options(8, Split::EqualArea),
    )
    .unwrap();
    // A rigid translation keeps the cost.
    for p in &mut pos {
        *p += Vec3A::new(0.3, -0.2, 0.1);
    }
    let report = bvh
        .refit(&Triangles::from_mesh(&mesh, &pos).unwrap())
        .unwrap();
    assert!((report.cost / bvh.build_cost() - 1.0).abs() < 1e-3);
    // Swirling the plane stretches the boxes of the original tree.
    for p in &mut pos {
        let r = (p.x * p.x + p.y * p.y).sqrt();
        let (s, c) = (6.0 * r).sin_cos();
        *p = Vec3A::new(c * p.x - s * p.y, s * p.x + c * p.y, p.z);
    }
    let tris = Triangles::from_mesh(&mesh, &pos).unwrap();
    let report = bvh.refit(&tris).unwrap();
    bvh.assert_well_formed(&tris);
    assert!(
        report.cost > 1.2 * bvh.build_cost(),
        "{} vs {}",
        report.cost,
        bvh.build_cost()
    );
    let stale = report.cost;
    bvh.rebuild(&tris, &mut Default::default()).unwrap();
    bvh.assert_well_formed(&tris);
    assert!(bvh.cost() < stale);
    assert_eq!(bvh.cost(), bvh.build_cost());
}

#[test]
fn margin_fattens_leaves_and_survives_refit() {
    let mesh = uv_sphere(12, 11, 1.0).unwrap();
    let mut pos = to_vec3a(mesh.positions());
    let margin = 0.05;
    let opts = BuildOptions {
        margin,
        ..options(4, Split::EqualArea)
    };
    let mut bvh = Bvh::build(&Triangles::from_mesh(&mesh, &pos).unwrap(), &opts).unwrap();
    let check = |bvh: &Bvh, pos: &[Vec3A]| {
        let tris = Triangles::from_mesh(&mesh, pos).unwrap();
        bvh.assert_well_formed(&tris);
        for i in 0..bvh.node_count() as u32 {
            if bvh.nodes()[i as usize].is_leaf() {
                let tight = bvh
                    .leaf_primitives(i)
                    .iter()
                    .fold(Aabb::EMPTY, |b, &p| b.union(&tris.bounds(p)));
                assert_eq!(bvh.nodes()[i as usize].aabb, tight.expanded(margin));
            }
        }
    };
    check(&bvh, &pos);
    jitter(&mut pos, &mut Rng::new(3), 0.01);
    bvh.refit(&Triangles::from_mesh(&mesh, &pos).unwrap())
        .unwrap();
    check(&bvh, &pos);
}

#[test]
fn box_point_and_ray_queries_match_brute_force() {
    let mesh = scenes::triangle_soup(11, 2000, 1.0, 0.04).unwrap();
    let pos = to_vec3a(mesh.positions());
    let tris = Triangles::from_mesh(&mesh, &pos).unwrap();
    let mut ws = BvhWorkspace::new();
    let mut rng = Rng::new(5);
    for split in [Split::EqualArea, Split::Sah] {
        let bvh = Bvh::build(&tris, &options(5, split)).unwrap();
        let mut out = Vec::new();
        let mut leaves = Vec::new();
        for _ in 0..200 {
            // Box.
            let c = rng.in_cube(0.6);
            let h = Vec3::splat(rng.range(0.0, 0.1));
            let probe = Aabb::new(Vec3::from(c) - h, Vec3::from(c) + h);
            bvh.overlapping_primitives(&tris, &probe, 0.0, &mut ws, &mut out);
            let mut want: Vec<u32> = (0..2000)
                .filter(|&t| tris.bounds(t).overlaps(&probe, 0.0))
                .collect();
            out.sort_unstable();
            want.sort_unstable();
            assert_eq!(out, want);
            bvh.overlapping_leaves(&probe, 0.0, &mut ws, &mut leaves);
            let from_leaves: usize = leaves
                .iter()
                .map(|&l| {
                    bvh.leaf_primitives(l)
                        .iter()
                        .filter(|&&t| tris.bounds(t).overlaps(&probe, 0.0))
                        .count()
                })
                .sum();
            assert_eq!(from_leaves, want.len());

            // Point.
            let p = rng.in_cube(0.8);
            let hit = bvh.closest_point(&tris, p, f32::INFINITY, &mut ws).unwrap();
            let brute = (0..2000u32)
                .map(|t| {
                    let [a, b, c] = tris.corners(t);
                    (tissue_bvh::closest_point_on_triangle(p, a, b, c).0 - p).length()
                })
                .fold(f32::INFINITY, f32::min);
            assert!(
                (hit.distance - brute).abs() <= 1e-6,
                "{} vs {brute}",
                hit.distance
            );
            assert!(bvh.closest_point(&tris, p, brute * 0.5, &mut ws).is_none() || brute == 0.0);

            // Ray.
            let ray = Ray::new(rng.in_cube(0.8), rng.in_cube(1.0));
            let hit = bvh.cast_ray(&tris, &ray, 10.0, &mut ws);
            let brute = (0..2000u32)
                .filter_map(|t| {
                    let [a, b, c] = tris.corners(t);
                    tissue_bvh::ray_triangle(ray.origin, ray.dir, 10.0, a, b, c).map(|h| h.0)
                })
                .fold(f32::INFINITY, f32::min);
            match hit {
                Some(h) => assert_eq!(h.t, brute),
                None => assert!(brute.is_infinite()),
            }
        }
    }
}

#[test]
fn boxes_are_primitives_too() {
    let mut rng = Rng::new(9);
    let boxes: Vec<Aabb> = (0..500)
        .map(|_| {
            let c = Vec3::from(rng.in_cube(1.0));
            Aabb::new(c, c + Vec3::from(rng.in_cube(0.05).abs()))
        })
        .collect();
    let bvh = Bvh::build(boxes.as_slice(), &options(2, Split::EqualArea)).unwrap();
    bvh.assert_well_formed(boxes.as_slice());
    let mut ws = BvhWorkspace::new();
    let got = bvh_pairs(&bvh, boxes.as_slice(), &bvh, boxes.as_slice(), 0.0, &mut ws);
    assert_same_pairs(
        got,
        brute_pairs(boxes.as_slice(), boxes.as_slice(), 0.0),
        "self pairs",
    );
}

#[test]
fn errors_name_what_is_wrong() {
    let mesh = grid(3, 1.0).unwrap();
    let mut pos = to_vec3a(mesh.positions());
    let tris = Triangles::from_mesh(&mesh, &pos).unwrap();
    assert_eq!(
        Bvh::build(&tris, &options(0, Split::EqualArea)).unwrap_err(),
        BvhError::InvalidLeafSize { leaf_size: 0 }
    );
    let bad_margin = BuildOptions {
        margin: -1.0,
        ..Default::default()
    };
    assert!(matches!(
        Bvh::build(&tris, &bad_margin),
        Err(BvhError::InvalidMargin { .. })
    ));
    let empty: &[Aabb] = &[];
    assert_eq!(
        Bvh::build(empty, &BuildOptions::default()).unwrap_err(),
        BvhError::Empty
    );
    assert!(matches!(
        Triangles::from_mesh(&mesh, &pos[..3]),
        Err(BvhError::PositionCount {
            expected: 9,
            got: 3
        })
    ));
    assert!(matches!(
        Triangles::new(&pos, &[[0, 1, 9]]),
        Err(BvhError::IndexOutOfRange {
            triangle: 0,
            index: 9,
            vertex_count: 9
        })
    ));
    let mut bvh = Bvh::build(&tris, &options(2, Split::EqualArea)).unwrap();
    let other = grid(4, 1.0).unwrap();
    let other_pos = to_vec3a(other.positions());
    assert!(matches!(
        bvh.refit(&Triangles::from_mesh(&other, &other_pos).unwrap()),
        Err(BvhError::PrimitiveCount {
            expected: 8,
            got: 18
        })
    ));
    // A diverged vertex: both build and refit name a triangle that uses it.
    pos[4].x = f32::NAN;
    let tris = Triangles::from_mesh(&mesh, &pos).unwrap();
    let uses_4 = |p: u32| mesh.triangles()[p as usize].contains(&4);
    match Bvh::build(&tris, &BuildOptions::default()) {
        Err(BvhError::NonFiniteBounds { primitive, .. }) => assert!(uses_4(primitive)),
        other => panic!("{other:?}"),
    }
    match bvh.refit(&tris) {
        Err(BvhError::NonFiniteBounds { primitive, .. }) => assert!(uses_4(primitive)),
        other => panic!("{other:?}"),
    }
    let msg = BvhError::InvalidLeafSize { leaf_size: 0 }.to_string();
    assert!(msg.contains("leaf size 0"), "{msg}");
}

// Bounded generators for the property tests.
mod strategies {
    use super::*;

    /// A seed, a triangle count and a triangle size for [`scenes::triangle_soup`].
    pub fn soup() -> impl Strategy<Value = (u64, usize, f32)> {
        (any::<u64>(), 1usize..300, 0.01f32..0.3)
    }

    pub fn split() -> impl Strategy<Value = Split> {
        prop_oneof![Just(Split::EqualArea), Just(Split::Sah)]
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn any_soup_builds_well_formed(
        (seed, count, size) in strategies::soup(),
        leaf_size in 1u32..20,
        split in strategies::split(),
    ) {
        let mesh = scenes::triangle_soup(seed, count, 1.0, size).unwrap();
        let pos = to_vec3a(mesh.positions());
        let tris = Triangles::from_mesh(&mesh, &pos).unwrap();
        let bvh = Bvh::build(&tris, &options(leaf_size, split)).unwrap();
        bvh.assert_well_formed(&tris);
    }

    #[test]
    fn pair_sets_are_symmetric(
        a in strategies::soup(),
        b in strategies::soup(),
        gap in 0.0f32..0.05,
    ) {
        let ma = scenes::triangle_soup(a.0, a.1, 1.0, a.2).unwrap();
        let mb = scenes::triangle_soup(b.0, b.1, 1.0, b.2).unwrap();
        let (pa, pb) = (to_vec3a(ma.positions()), to_vec3a(mb.positions()));
        let ta = Triangles::from_mesh(&ma, &pa).unwrap();
        let tb = Triangles::from_mesh(&mb, &pb).unwrap();
        let ba = Bvh::build(&ta, &options(4, Split::EqualArea)).unwrap();
        let bb = Bvh::build(&tb, &options(2, Split::Sah)).unwrap();
        let mut ws = BvhWorkspace::new();
        let ab = bvh_pairs(&ba, &ta, &bb, &tb, gap, &mut ws);
        let ba_swapped: Vec<[u32; 2]> =
            bvh_pairs(&bb, &tb, &ba, &ta, gap, &mut ws).into_iter().map(|[x, y]| [y, x]).collect();
        prop_assert_eq!(summary(&ab), summary(&ba_swapped));
        prop_assert_eq!(summary(&ab), summary(&brute_pairs(&ta, &tb, gap)));
    }
}
