//! Region selection and geodesic distances through the public API: against exact distances on a
//! plane and a sphere, against edge-graph Dijkstra, the region's shape, the errors, and a real
//! head scan.
#![allow(clippy::unwrap_used)]

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::f64::consts::PI;

use glam::Vec3;
use tissue_implant::{
    default_radius, geodesic_distances, select_region, select_region_with, snap_to_surface,
    ImplantError, Param, RegionOptions, RegionRule, RegionSelection, NOT_IN_REGION,
};
use tissue_mesh::TriMesh;

/// Edge length of `grid(65, 20.0)`.
const GRID_EDGE: f64 = 20.0 / 64.0;

/// Plain Dijkstra over the edge graph from vertices at given distances (what the geodesic must
/// beat).
fn dijkstra(mesh: &TriMesh, sources: &[(u32, f64)]) -> Vec<f64> {
    let n = mesh.vertex_count();
    let mut adjacency = vec![Vec::new(); n];
    for &[a, b] in mesh.topology().edges() {
        let len = f64::from(mesh.positions()[a as usize].distance(mesh.positions()[b as usize]));
        adjacency[a as usize].push((b, len));
        adjacency[b as usize].push((a, len));
    }
    let mut dist = vec![f64::INFINITY; n];
    let mut heap = BinaryHeap::new();
    for &(v, d) in sources {
        dist[v as usize] = d;
        heap.push(Reverse((d.to_bits(), v)));
    }
    while let Some(Reverse((bits, v))) = heap.pop() {
        let d = f64::from_bits(bits);
        if d > dist[v as usize] {
            continue;
        }
        for &(w, len) in &adjacency[v as usize] {
            if d + len < dist[w as usize] {
                dist[w as usize] = d + len;
                // Non-negative f64s order like their bit patterns.
                heap.push(Reverse(((d + len).to_bits(), w)));
            }
        }
    }
    dist
}

/// Euclidean distance of every vertex from `p`.
fn euclidean(mesh: &TriMesh, p: Vec3) -> Vec<f64> {
    mesh.positions()
        .iter()
        .map(|q| q.as_dvec3().distance(p.as_dvec3()))
        .collect()
}

fn options(rule: RegionRule) -> RegionOptions {
    RegionOptions {
        rule,
        ..RegionOptions::default()
    }
}

/// Largest `|d − exact|` over the vertices where `keep` holds, and the vertex.
fn worst(d: &[f64], exact: &[f64], keep: impl Fn(usize) -> bool) -> (f64, usize) {
    (0..d.len())
        .filter(|&v| keep(v))
        .map(|v| ((d[v] - exact[v]).abs(), v))
        .fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a })
}

/// Test 1. On the flat 65 × 65 grid (edge h = 0.3125 cm) the geodesic distance equals the
/// Euclidean distance to within 1e-4·h (the method is exact on a plane; only rounding is left),
/// from the centre vertex and from a point inside a triangle. Edge-graph Dijkstra, on the same
/// mesh, overestimates by more than 7 % between the grid's axes and diagonals (at 22.5°, its paths
/// zig-zag; on the axes and the union-jack diagonals it is exact), far outside that tolerance.
#[test]
fn plane_geodesic_is_euclidean_and_beats_dijkstra() {
    let plane = tissue_mesh::grid(65, 20.0).unwrap();
    let tolerance = 1e-4 * GRID_EDGE;
    for query in [Vec3::ZERO, Vec3::new(0.37, -0.21, 0.0)] {
        let source = snap_to_surface(&plane, query, 1e-3).unwrap();
        let d = geodesic_distances(&plane, &source, f64::INFINITY).unwrap();
        let exact = euclidean(&plane, query);
        let (err, v) = worst(&d, &exact, |_| true);
        eprintln!(
            "plane from {query}: largest |geodesic − euclidean| = {err:.2e} cm at vertex {v}"
        );
        assert!(err <= tolerance, "{err} > {tolerance} at vertex {v}");
    }
    let centre = 32 * 65 + 32;
    let graph = dijkstra(&plane, &[(centre, 0.0)]);
    let exact = euclidean(&plane, Vec3::ZERO);
    let beyond_three_rings = |v: usize| exact[v] > 3.0 * GRID_EDGE;
    let relative = |v: usize| graph[v] / exact[v] - 1.0;
    let worst_relative = (0..plane.vertex_count())
        .filter(|&v| beyond_three_rings(v))
        .map(relative)
        .fold(0.0, f64::max);
    eprintln!(
        "plane: Dijkstra overestimates by up to {:.2} %",
        100.0 * worst_relative
    );
    assert!(worst_relative > 0.07, "{worst_relative}");
    // Along the 22.5° direction, 8 cm out, Dijkstra is off by far more than the tolerance.
    let towards = Vec3::new(8.0 * 0.9238795, 8.0 * 0.3826834, 0.0);
    let probe = (0..plane.vertex_count())
        .min_by(|&a, &b| {
            let (pa, pb) = (plane.positions()[a], plane.positions()[b]);
            pa.distance(towards).total_cmp(&pb.distance(towards))
        })
        .unwrap();
    let excess = graph[probe] - exact[probe];
    eprintln!(
        "plane: at vertex {probe} ({:.2} cm out at 22.5°) Dijkstra is {excess:.3} cm too long",
        exact[probe]
    );
    assert!(excess > 1000.0 * tolerance, "{excess}");
}

/// A flat grid sheared by 40° has obtuse angles of 130° everywhere, and is still a plane: the
/// geodesic stays within 1 % of the edge length of the Euclidean distance (measured: 3·10⁻⁸ cm,
/// the rounding of the sheared `f32` positions). Obtuse corners are split by unfolding, and what
/// that misses the correction pass repairs; without both, corners would keep paths through
/// vertices.
#[test]
fn sheared_plane_with_obtuse_triangles_stays_euclidean() {
    let grid = tissue_mesh::grid(41, 10.0).unwrap();
    let shear = 40f32.to_radians().tan();
    let positions = grid
        .positions()
        .iter()
        .map(|p| Vec3::new(p.x + shear * p.y, p.y, 0.0))
        .collect();
    let plane = grid.with_positions(positions).unwrap();
    let edge = 10.0 / 40.0;
    let query = Vec3::new(0.1, 0.05, 0.0);
    let source = snap_to_surface(&plane, query, 1e-3).unwrap();
    let d = geodesic_distances(&plane, &source, f64::INFINITY).unwrap();
    let exact = euclidean(&plane, query);
    let (err, v) = worst(&d, &exact, |_| true);
    eprintln!("sheared plane: largest |geodesic − euclidean| = {err:.2e} cm at vertex {v}");
    assert!(err <= 0.01 * edge, "{err} at vertex {v}");
}

/// Test 2. On a UV sphere of radius 1 with 64 segments and 63 rings (edges ≤ 0.05), the distance
/// from the north pole equals the great-circle distance `acos(z)` to within 0.1 % (the inscribed
/// polyhedron's meridians alone are 0.01 % shorter than the arcs). From a point on the equator,
/// where the geodesics cross the triangles obliquely, it is within 0.6 % of the great-circle
/// distance over the quarter circle around the point (beyond the first four rings: a disc far more
/// curved than any skin region) and within 2 % up to the antipode, where all geodesics meet;
/// edge-graph Dijkstra is off by more than 3 % there.
#[test]
fn sphere_geodesic_is_the_great_circle_distance() {
    let sphere = tissue_mesh::uv_sphere(64, 63, 1.0).unwrap();
    let pole = snap_to_surface(&sphere, Vec3::new(0.0, 0.0, 1.2), 0.5).unwrap();
    assert_eq!(pole.position(), Vec3::Z);
    let (relative, absolute) = great_circle_error(&sphere, &pole, 0.0, PI);
    eprintln!(
        "sphere from the pole: largest error {:.3} % ({absolute:.2e} on radius 1)",
        100.0 * relative
    );
    assert!(relative < 0.001, "{relative}");

    let side = snap_to_surface(&sphere, Vec3::new(0.6, 0.8, 0.01), 0.01).unwrap();
    let quarter = std::f64::consts::FRAC_PI_2;
    let (relative, absolute) = great_circle_error(&sphere, &side, 0.2, quarter);
    eprintln!(
        "sphere from the equator: largest error {:.3} % ({absolute:.2e}) from 0.2 to π/2",
        100.0 * relative
    );
    assert!(relative < 0.006, "{relative}");
    let (relative, absolute) = great_circle_error(&sphere, &side, 0.2, PI);
    eprintln!(
        "sphere from the equator: largest error {:.3} % ({absolute:.2e}) from 0.2 to π",
        100.0 * relative
    );
    assert!(relative < 0.02, "{relative}");
    let start = sphere.triangles()[side.triangle() as usize][0];
    let graph = dijkstra(&sphere, &[(start, 0.0)]);
    let from = sphere.positions()[start as usize].as_dvec3().normalize();
    let graph_relative = sphere
        .positions()
        .iter()
        .zip(&graph)
        .map(|(p, &g)| {
            let exact = p.as_dvec3().normalize().dot(from).clamp(-1.0, 1.0).acos();
            if exact > 0.2 {
                g / exact - 1.0
            } else {
                0.0
            }
        })
        .fold(0.0, f64::max);
    eprintln!(
        "sphere from the equator: Dijkstra overestimates by up to {:.2} %",
        100.0 * graph_relative
    );
    assert!(graph_relative > 0.03, "{graph_relative}");
}

/// Largest relative and absolute difference between the geodesic distance from `source` and the
/// great-circle distance (on the unit sphere, between directions), over vertices whose
/// great-circle distance lies in `(beyond, to]`.
fn great_circle_error(
    sphere: &TriMesh,
    source: &tissue_implant::SurfacePoint,
    beyond: f64,
    to: f64,
) -> (f64, f64) {
    let d = geodesic_distances(sphere, source, f64::INFINITY).unwrap();
    let from = source.position().as_dvec3().normalize();
    let (mut relative, mut absolute) = (0.0f64, 0.0f64);
    for (v, p) in sphere.positions().iter().enumerate() {
        let exact = p.as_dvec3().normalize().dot(from).clamp(-1.0, 1.0).acos();
        if exact > beyond && exact > 0.0 && exact <= to {
            relative = relative.max((d[v] - exact).abs() / exact);
            absolute = absolute.max((d[v] - exact).abs());
        }
    }
    (relative, absolute)
}

/// Test 3. A region of radius 5 cm on the 20 cm plane: area πr² to within 1 % (the centroid rule
/// puts triangles on both sides of the circle; one ring of triangles would be 2πr·h/2 ≈ 6 %),
/// exactly one boundary loop, one component, and boundary vertices within one edge length of
/// `d = r`.
#[test]
fn plane_region_is_a_disc_of_area_pi_r_squared() {
    let plane = tissue_mesh::grid(65, 20.0).unwrap();
    let r = 5.0;
    let region = select_region(&plane, Vec3::new(0.4, 0.3, 0.0), r).unwrap();
    let disc = PI * r * r;
    eprintln!(
        "plane region r = {r}: area {:.3} cm² vs πr² = {disc:.3} ({:+.2} %), {} vertices",
        region.area(),
        100.0 * (region.area() / disc - 1.0),
        region.mesh().vertex_count()
    );
    assert!((region.area() - disc).abs() < 0.01 * disc);
    assert_eq!(region.boundary_loops().len(), 1);
    assert_eq!(region.mesh().topology().component_count(), 1);
    for &v in &region.boundary_loops()[0] {
        let d = region.distances()[v as usize];
        assert!((d - r).abs() <= GRID_EDGE, "boundary vertex {v} at {d}");
    }
    // Every region vertex is within r + h; every patient vertex within r − h is in the region.
    for (v, &d) in region.patient_distances().iter().enumerate() {
        let inside = region.patient_to_region()[v] != NOT_IN_REGION;
        if d < r - GRID_EDGE {
            assert!(inside, "vertex {v} at {d} left out");
        }
        if inside {
            assert!(d <= r + GRID_EDGE, "vertex {v} at {d} taken in");
        }
    }
}

/// The thesis's rule (every triangle with a corner within the radius) gives the thesis's region
/// on its 20 cm plane under a 7 cm base (92.57 cm² there, `default_radius(3.5)` = 5.25 cm here).
#[test]
fn touching_rule_reproduces_the_thesis_region() {
    let plane = tissue_mesh::grid(65, 20.0).unwrap();
    let r = default_radius(3.5).unwrap();
    let thesis =
        select_region_with(&plane, Vec3::ZERO, r, &options(RegionRule::TouchesVertex)).unwrap();
    let ours = select_region(&plane, Vec3::ZERO, r).unwrap();
    eprintln!(
        "r = {r}: touching rule {:.2} cm² ({} vertices), centroid rule {:.2} cm² ({} vertices)",
        thesis.area(),
        thesis.mesh().vertex_count(),
        ours.area(),
        ours.mesh().vertex_count()
    );
    assert!((thesis.area() - 92.57).abs() < 0.02 * 92.57);
    assert!((ours.area() - PI * r * r).abs() < 0.01 * PI * r * r);
}

/// Test 4a. A point 3 mm above the plane snaps straight down onto it.
#[test]
fn point_just_off_the_surface_snaps_to_the_nearest_point() {
    let plane = tissue_mesh::grid(65, 20.0).unwrap();
    let region = select_region(&plane, Vec3::new(1.23, -2.34, 0.3), 4.0).unwrap();
    let c = region.centre();
    assert!((c.position() - Vec3::new(1.23, -2.34, 0.0)).length() < 1e-6);
    assert!((c.distance() - 0.3).abs() < 1e-6);
    let [a, b, d] = plane.corners(c.triangle() as usize);
    let [u, v, w] = c.barycentric();
    assert!((a * u + b * v + d * w - c.position()).length() < 1e-5);
    // And onto a sphere from outside, along the radius.
    let sphere = tissue_mesh::uv_sphere(32, 31, 2.0).unwrap();
    let p = snap_to_surface(&sphere, Vec3::new(1.0, 1.0, 1.5) * 1.1, 1.0).unwrap();
    let dir = p.position().normalize();
    assert!(dir.dot(Vec3::new(1.0, 1.0, 1.5).normalize()) > 0.9999);
}

/// Test 4b. A point far from the surface is an error that names its distance.
#[test]
fn far_point_is_an_error_naming_the_distance() {
    let plane = tissue_mesh::grid(65, 20.0).unwrap();
    let err = select_region(&plane, Vec3::new(0.0, 0.0, 5.0), 4.0).unwrap_err();
    match &err {
        ImplantError::PointOffSurface {
            distance,
            max_distance,
            nearest,
            ..
        } => {
            assert!((distance - 5.0).abs() < 1e-6);
            assert!((max_distance - 0.05 * 800f64.sqrt()).abs() < 1e-5);
            assert_eq!(nearest, &[0.0, 0.0, 0.0]);
        }
        other => panic!("{other:?}"),
    }
    assert!(err.to_string().contains("5.000 cm"), "{err}");
    // A caller's own limit is honoured.
    let generous = RegionOptions {
        max_snap_distance: Some(6.0),
        ..RegionOptions::default()
    };
    assert!(select_region_with(&plane, Vec3::new(0.0, 0.0, 5.0), 4.0, &generous).is_ok());
}

/// Test 4c. A radius that is not positive and finite is refused.
#[test]
fn radius_must_be_positive_and_finite() {
    let plane = tissue_mesh::grid(17, 4.0).unwrap();
    for r in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let err = select_region(&plane, Vec3::ZERO, r).unwrap_err();
        assert!(
            matches!(
                err,
                ImplantError::InvalidParameter {
                    param: Param::Radius,
                    ..
                }
            ),
            "{r}: {err:?}"
        );
    }
    let err = select_region(&plane, Vec3::new(f32::NAN, 0.0, 0.0), 1.0).unwrap_err();
    assert!(matches!(
        err,
        ImplantError::InvalidParameter {
            param: Param::Point,
            ..
        }
    ));
}

/// Test 4d. A radius that takes in the whole plane is an error (no skin left to hold the
/// boundary), also on a closed sphere; one just short of it is not.
#[test]
fn radius_covering_the_whole_surface_is_an_error() {
    let plane = tissue_mesh::grid(17, 4.0).unwrap();
    let err = select_region(&plane, Vec3::ZERO, 10.0).unwrap_err();
    match err {
        ImplantError::RegionCoversSurface {
            triangles,
            farthest,
            ..
        } => {
            assert_eq!(triangles, plane.triangle_count());
            assert!((farthest - 8f64.sqrt()).abs() < 1e-5, "{farthest}");
        }
        other => panic!("{other:?}"),
    }
    assert!(select_region(&plane, Vec3::ZERO, 2.5).is_ok());
    let sphere = tissue_mesh::uv_sphere(16, 15, 1.0).unwrap();
    let err = select_region(&sphere, Vec3::Z, 4.0).unwrap_err();
    assert!(
        matches!(err, ImplantError::RegionCoversSurface { .. }),
        "{err:?}"
    );
    let cap = select_region(&sphere, Vec3::Z, 2.5).unwrap();
    assert_eq!(cap.boundary_loops().len(), 1);
}

/// Test 4e. A radius below the first ring of triangles leaves nothing: an error giving the radius
/// that would keep the centre's triangle.
#[test]
fn radius_below_the_first_ring_is_an_empty_region() {
    let plane = tissue_mesh::grid(65, 20.0).unwrap();
    let err = select_region(&plane, Vec3::ZERO, 0.1).unwrap_err();
    match err {
        ImplantError::EmptyRegion { min_radius, .. } => {
            // The centre vertex's triangle has corners at 0, h and h√2.
            let expected = GRID_EDGE * (1.0 + 2f64.sqrt()) / 3.0;
            assert!((min_radius - expected).abs() < 1e-6, "{min_radius}");
            let region = select_region(&plane, Vec3::ZERO, min_radius + 1e-9).unwrap();
            assert!(region.mesh().triangle_count() >= 1);
        }
        other => panic!("{other:?}"),
    }
}

/// Two parallel sheets 0.5 cm apart: the other sheet is near in space but unreachable along the
/// surface, so its distances are infinite and the region stays on the centre's sheet.
#[test]
fn region_does_not_jump_across_a_gap() {
    let sheet = tissue_mesh::grid(21, 6.0).unwrap();
    let (mut positions, mut triangles) = sheet.clone().into_parts();
    let n = positions.len() as u32;
    positions.extend(
        sheet
            .positions()
            .iter()
            .map(|p| *p + Vec3::new(0.0, 0.0, 0.5)),
    );
    triangles.extend(sheet.triangles().iter().map(|t| t.map(|v| v + n)));
    let two = TriMesh::new(positions, triangles).unwrap();
    let region = select_region(&two, Vec3::new(0.0, 0.0, 0.1), 2.0).unwrap();
    assert!(region.region_to_patient().iter().all(|&v| v < n));
    let source = snap_to_surface(&two, Vec3::new(0.0, 0.0, 0.1), 1.0).unwrap();
    let d = geodesic_distances(&two, &source, f64::INFINITY).unwrap();
    assert!(d[..n as usize].iter().all(|x| x.is_finite()));
    assert!(d[n as usize..].iter().all(|&x| x == f64::INFINITY));
}

/// The region's maps and numbering: vertices in patient order, maps inverse to each other.
#[test]
fn region_maps_are_inverse_and_in_patient_order() {
    let plane = tissue_mesh::grid(65, 20.0).unwrap();
    let region = select_region(&plane, Vec3::new(-3.0, 2.0, 0.0), 3.0).unwrap();
    check_maps(&region, &plane);
}

fn check_maps(region: &RegionSelection, patient: &TriMesh) {
    let map = region.region_to_patient();
    assert!(map.windows(2).all(|w| w[0] < w[1]));
    for (i, &v) in map.iter().enumerate() {
        assert_eq!(region.patient_to_region()[v as usize], i as u32);
        assert_eq!(
            region.mesh().positions()[i],
            patient.positions()[v as usize]
        );
    }
    for (t, &pt) in region.triangle_to_patient().iter().enumerate() {
        let tri = region.mesh().triangles()[t].map(|v| map[v as usize]);
        assert_eq!(tri, patient.triangles()[pt as usize]);
    }
    assert_eq!(
        region.triangle_to_patient()[region.centre_triangle() as usize],
        region.centre().triangle()
    );
}

/// Test 5. On the MakeHuman head (decimetres, scaled to cm), regions of radius 4 cm on the
/// forehead and the cheek are one piece with one boundary loop and an area within 30 % of πr²;
/// every distance lies between the straight-line distance and edge-graph Dijkstra's.
#[test]
fn head_regions_on_forehead_and_cheek_are_discs() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/makehuman_head_open.obj"
    );
    let head_dm = tissue_meshio::read_surface(path).unwrap();
    let (positions, triangles) = head_dm.into_parts();
    let head = TriMesh::new(positions.iter().map(|p| *p * 10.0).collect(), triangles).unwrap();
    let b = head.bounding_box();
    eprintln!(
        "head: {} vertices, box {:?} – {:?} cm",
        head.vertex_count(),
        b.min,
        b.max
    );
    let r = 4.0;
    let disc = PI * r * r;
    // Points in front of the face (+z), snapped back onto it.
    for (name, query) in [
        ("forehead", Vec3::new(0.0, 79.0, 16.0)),
        ("cheek", Vec3::new(7.0, 67.0, 12.0)),
    ] {
        let options = RegionOptions {
            max_snap_distance: Some(3.0),
            ..RegionOptions::default()
        };
        let region = select_region_with(&head, query, r, &options).unwrap();
        let c = region.centre();
        eprintln!(
            "head {name}: centre {} ({:.2} cm from the query), {} vertices, {} triangles, \
             area {:.2} cm² = {:.3}·πr², {} loop(s)",
            c.position(),
            c.distance(),
            region.mesh().vertex_count(),
            region.mesh().triangle_count(),
            region.area(),
            region.area() / disc,
            region.boundary_loops().len()
        );
        assert_eq!(region.mesh().topology().component_count(), 1, "{name}");
        assert_eq!(region.boundary_loops().len(), 1, "{name}");
        assert!(
            (0.7 * disc..1.3 * disc).contains(&region.area()),
            "{name}: {}",
            region.area()
        );
        check_maps(&region, &head);
        // Bounds on the whole head: chord ≤ geodesic ≤ edge paths.
        let d = geodesic_distances(&head, c, f64::INFINITY).unwrap();
        let seeds = head.triangles()[c.triangle() as usize].map(|v| {
            (
                v,
                head.positions()[v as usize]
                    .as_dvec3()
                    .distance(c.position().as_dvec3()),
            )
        });
        let graph = dijkstra(&head, &seeds);
        let chord = euclidean(&head, c.position());
        for v in 0..head.vertex_count() {
            assert!(d[v] >= chord[v] * (1.0 - 1e-9), "{name}: vertex {v}");
            assert!(d[v] <= graph[v] * (1.0 + 1e-9), "{name}: vertex {v}");
        }
    }
}
