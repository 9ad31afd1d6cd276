//! Closed-form checks of the measures on generated meshes: exact plane and cube areas and volumes,
//! the UV sphere against its polyhedral volume and area derived independently below, the volume
//! between a disc and a spherical cap against the cap formula with a derived discretisation bound
//! and its second-order convergence, and invariance under rigid motions.
#![allow(clippy::expect_used)]

use std::f64::consts::PI;

use glam::{DQuat, DVec3, Vec3};
use proptest::prelude::*;
use tissue_mesh::{
    diagnose, disc, grid, subdivided_cube, uv_sphere, volume_between, MeshError, TriMesh,
};

/// Unit roundoff of `f64`, `2⁻⁵³`.
const U: f64 = f64::EPSILON / 2.0;
/// Largest relative rounding of an `f64` value cast to `f32`, `2⁻²⁴`.
const U32: f64 = f32::EPSILON as f64 / 2.0;

/// Half the sum of the triangle perimeters, `Σ_t P_t / 2`: the first-order sensitivity of the
/// area to moving every coordinate by at most 1 (`|∂A_t/∂x_v|` is half the edge opposite `v`),
/// up to the factor `√3` from three coordinates.
fn half_perimeter_sum(m: &TriMesh) -> f64 {
    (0..m.triangle_count())
        .map(|t| {
            let [a, b, c] = m.corners(t).map(|p| p.as_dvec3());
            ((b - a).length() + (c - b).length() + (a - c).length()) / 2.0
        })
        .sum()
}

fn max_abs_coordinate(m: &TriMesh) -> f64 {
    m.positions()
        .iter()
        .map(|p| f64::from(p.abs().max_element()))
        .fold(0.0, f64::max)
}

/// A copy of `m` with the winding of every triangle reversed.
fn reversed(m: &TriMesh) -> TriMesh {
    let triangles = m.triangles().iter().map(|&[a, b, c]| [a, c, b]).collect();
    TriMesh::new(m.positions().to_vec(), triangles).expect("reversing keeps a surface valid")
}

// ---------------------------------------------------------------------------------------------
// Generators: counts, validity, determinism.

#[test]
fn grid_counts_match_the_thesis_planes() {
    for (n, vertices, triangles) in [(65, 4225, 8192), (129, 16641, 32768), (257, 66049, 131072)] {
        let g = grid(n, 1.0).unwrap();
        assert_eq!(
            (g.vertex_count(), g.triangle_count()),
            (vertices, triangles)
        );
        assert!(diagnose(g.positions(), g.triangles()).is_empty());
        assert_eq!(g.topology().boundary_loops().len(), 1);
        assert_eq!(g.euler_characteristic(), 1);
        assert!(g.triangle_normals().iter().all(|&nrm| nrm == Vec3::Z));
        let b = g.bounding_box();
        assert_eq!(
            (b.min, b.max),
            (Vec3::new(-0.5, -0.5, 0.0), Vec3::new(0.5, 0.5, 0.0))
        );
    }
}

#[test]
fn grid_diagonals_alternate_so_interior_degrees_alternate_between_4_and_8() {
    let g = grid(9, 1.0).unwrap();
    let n = 9u32;
    for row in 1..n - 1 {
        for col in 1..n - 1 {
            let degree = g.topology().vertex_triangles(row * n + col).len();
            let expected = if (row + col) % 2 == 0 { 8 } else { 4 };
            assert_eq!(degree, expected, "vertex ({row}, {col})");
        }
    }
}

#[test]
fn uv_sphere_counts_radius_and_orientation() {
    for (segments, rings, vertices, triangles) in [(32, 31, 994, 1984), (12, 11, 134, 264)] {
        for r in [0.25f32, 1.0, 7.5] {
            let s = uv_sphere(segments, rings, r).unwrap();
            assert_eq!(
                (s.vertex_count(), s.triangle_count()),
                (vertices, triangles)
            );
            assert!(diagnose(s.positions(), s.triangles()).is_empty());
            assert!(s.is_closed());
            assert_eq!(s.euler_characteristic(), 2);
            // Each coordinate is within half an f32 ulp (≤ 2⁻²⁴ r) of the exact point.
            let r = f64::from(r);
            for p in s.positions() {
                let d = p.as_dvec3().length();
                assert!((d - r).abs() <= 3f64.sqrt() * U32 * r, "|p| = {d}, r = {r}");
            }
            assert_eq!(s.positions()[0], Vec3::new(0.0, 0.0, r as f32));
            assert_eq!(s.positions()[vertices - 1], Vec3::new(0.0, 0.0, -r as f32));
            // Outward: every vertex normal points away from the centre.
            for (p, nrm) in s.positions().iter().zip(s.vertex_normals()) {
                assert!(p.normalize().dot(nrm) > 0.99);
            }
            assert!(s.signed_volume().unwrap() > 0.0);
        }
    }
}

#[test]
fn subdivided_cube_counts_and_outward_normals() {
    let c = subdivided_cube(8, 2.0).unwrap();
    assert_eq!((c.vertex_count(), c.triangle_count()), (386, 768));
    assert!(diagnose(c.positions(), c.triangles()).is_empty());
    assert!(c.is_closed());
    assert_eq!(c.euler_characteristic(), 2);
    assert_eq!(c.topology().component_count(), 1);
    for t in 0..c.triangle_count() {
        let centre = c.corners(t).iter().copied().sum::<Vec3>() / 3.0;
        let nrm = c.triangle_normals()[t];
        // The normal is the axis of the face the triangle lies on, pointing away from the centre.
        assert!((nrm.dot(centre) - centre.abs().max_element()).abs() < 1e-6);
    }
}

#[test]
fn disc_counts_and_boundary() {
    for (radial, segments) in [(1, 3), (4, 16), (16, 64)] {
        let d = disc(radial, segments, 1.5).unwrap();
        let (radial, segments) = (radial as usize, segments as usize);
        assert_eq!(d.vertex_count(), 1 + radial * segments);
        assert_eq!(d.triangle_count(), segments * (2 * radial - 1));
        assert!(diagnose(d.positions(), d.triangles()).is_empty());
        assert_eq!(d.euler_characteristic(), 1);
        let loops = d.topology().boundary_loops();
        assert_eq!(loops.len(), 1);
        assert_eq!(loops[0].len(), segments);
        assert!(d.triangle_normals().iter().all(|&n| n == Vec3::Z));
        // Area of the boundary polygon, (m/2) a² sin(2π/m).
        let polygon = segments as f64 / 2.0 * 1.5f64.powi(2) * (2.0 * PI / segments as f64).sin();
        assert!((d.area() - polygon).abs() < 1e-6 * polygon);
    }
}

#[test]
fn generators_are_bit_for_bit_deterministic() {
    let bits = |m: &TriMesh| -> Vec<u32> {
        m.positions()
            .iter()
            .flat_map(|p| p.to_array().map(f32::to_bits))
            .collect()
    };
    let makers: [fn() -> Result<TriMesh, MeshError>; 4] = [
        || grid(33, 3.7),
        || uv_sphere(32, 31, 0.25),
        || subdivided_cube(5, 1.3),
        || disc(7, 24, 2.2),
    ];
    for make in makers {
        let (a, b) = (make().unwrap(), make().unwrap());
        assert_eq!(bits(&a), bits(&b));
        assert_eq!(a.triangles(), b.triangles());
    }
}

// ---------------------------------------------------------------------------------------------
// Areas and volumes against closed forms.

/// A grid of side L tiles the square `[−L/2, L/2]²` exactly: the lattice puts the boundary
/// vertices exactly on `±L/2` (L/2 is exact in f32 for these L), every row has one `y` and every
/// column one `x`, so the f32 triangles are right triangles that tile the square, and their exact
/// areas sum to exactly L². What remains is f64 rounding: differences of the f32 coordinates are
/// exact in f64; each triangle's cross product has one nonzero component formed with one rounded
/// product (the other term is an exact 0), `length()` squares and takes a square root, so each
/// area carries a relative error ≤ 2.5u (u = 2⁻⁵³); the left-to-right sum of N positive terms adds
/// ≤ (N − 1)u relative. Hence |area − L²| ≤ (N + 2)·u·L² (to first order; margin 1.01).
#[test]
fn plane_area_is_exact_up_to_summation_rounding() {
    for n in [2, 3, 65, 129, 257] {
        for side in [1.0f32, 0.3, 20.0] {
            let g = grid(n, side).unwrap();
            let exact = f64::from(side).powi(2);
            let bound = 1.01 * (g.triangle_count() as f64 + 2.0) * U * exact;
            let area = g.area();
            assert!(
                (area - exact).abs() <= bound,
                "n {n} side {side}: {area} vs {exact}"
            );
            let per_triangle: f64 = g.triangle_areas().iter().sum();
            assert!((per_triangle - exact).abs() <= bound);
        }
    }
}

/// Every lattice coordinate of `subdivided_cube(8, 2.0)` is a multiple of 1/8, so every product
/// and sum in the area and volume is exact in f64: the cube has area 24 and volume 8 (the
/// thesis's test cube, 386 vertices, 768 triangles).
#[test]
fn cube_of_side_2_has_volume_8_and_area_24() {
    let c = subdivided_cube(8, 2.0).unwrap();
    assert_eq!(c.area(), 24.0);
    assert_eq!(c.signed_volume().unwrap(), 8.0);
    assert!(c.centroid().length() < 1e-15);
    for per_edge in [1, 3, 7] {
        let c = subdivided_cube(per_edge, 2.0).unwrap();
        assert!((c.area() - 24.0).abs() < 1e-12);
        assert!((c.signed_volume().unwrap() - 8.0).abs() < 1e-12);
    }
}

/// Volume of the UV-sphere polyhedron from the closed-form vertex positions (not from the mesh).
///
/// With `m` segments, `k` rings, `δ = 2π/m`, `θ_i = πi/(k+1)` (`θ_0` and `θ_{k+1}` the poles) and
/// `s_i = sin θ_i`: the tetrahedron from the centre to the band triangles `(a, c, d)` and
/// `(a, d, b)` of the quad between rings `i` (`a`, `b`) and `i+1` (`c`, `d`) has `6V = r³ sin δ
/// sin(θ_{i+1} − θ_i)·s_{i+1}` and `r³ sin δ sin(θ_{i+1} − θ_i)·s_i` (a cap triangle is the case
/// `s = 0` at the pole), so `V = (r³/6)·m·sin δ·sin(π/(k+1))·Σ_i (s_i + s_{i+1}) =
/// (r³/3)·m·sin δ·sin(π/(k+1))·Σ_{i=1}^{k} s_i`, and `Σ s_i = cot(π/(2(k+1)))` gives
/// `V = (r³/3)·m·sin(2π/m)·(1 + cos(π/(k+1)))` (→ 4πr³/3 as m, k → ∞).
fn uv_sphere_polyhedron_volume(m: u32, k: u32, r: f64) -> f64 {
    let m = f64::from(m);
    r.powi(3) / 3.0 * m * (2.0 * PI / m).sin() * (1.0 + (PI / f64::from(k + 1)).cos())
}

/// Area of the UV-sphere polyhedron: each band quad is a planar isosceles trapezoid with parallel
/// chords `w_i = 2 r s_i sin(δ/2)` and height `h_i = r·√((s_i − s_{i+1})² cos²(δ/2) + (cos θ_i −
/// cos θ_{i+1})²)` (the distance between the chord midpoints); its two triangles have areas
/// `w_{i+1} h_i/2` and `w_i h_i/2` (a cap triangle is the case `w_0 = 0`).
fn uv_sphere_polyhedron_area(m: u32, k: u32, r: f64) -> f64 {
    let half = PI / f64::from(m);
    let theta = |i: u32| PI * f64::from(i) / f64::from(k + 1);
    let width = |i: u32| 2.0 * r * theta(i).sin() * half.sin();
    let band: f64 = (0..=k)
        .map(|i| {
            let (t0, t1) = (theta(i), theta(i + 1));
            let h = r
                * ((t0.sin() - t1.sin()).powi(2) * half.cos().powi(2)
                    + (t0.cos() - t1.cos()).powi(2))
                .sqrt();
            (width(i) + width(i + 1)) * h / 2.0
        })
        .sum();
    f64::from(m) * band
}

/// The mesh stores the closed-form positions rounded to f32, each coordinate by at most 2⁻²⁴·r.
/// Moving every coordinate by at most δ changes the volume by at most √3·δ·A and the area by at
/// most √3·δ·Σ_t P_t/2 (first order); the assertions allow twice that.
#[test]
fn uv_sphere_volume_and_area_match_the_polyhedron() {
    for (m, k) in [(32, 31), (12, 11)] {
        for r in [0.25f32, 1.0, 3.0] {
            let s = uv_sphere(m, k, r).unwrap();
            let r = f64::from(r);
            let delta = U32 * r;
            let (volume, area) = (s.signed_volume().unwrap(), s.area());
            let (exact_volume, exact_area) = (
                uv_sphere_polyhedron_volume(m, k, r),
                uv_sphere_polyhedron_area(m, k, r),
            );
            let volume_bound = 2.0 * 3f64.sqrt() * delta * area;
            let area_bound = 2.0 * 3f64.sqrt() * delta * half_perimeter_sum(&s);
            assert!(
                (volume - exact_volume).abs() <= volume_bound,
                "({m},{k}) r {r}: volume {volume} vs {exact_volume} (bound {volume_bound:e})"
            );
            assert!(
                (area - exact_area).abs() <= area_bound,
                "({m},{k}) r {r}: area {area} vs {exact_area} (bound {area_bound:e})"
            );
            // An inscribed polyhedron is smaller than its sphere in both measures.
            assert!(volume < 4.0 / 3.0 * PI * r.powi(3));
            assert!(area < 4.0 * PI * r.powi(2));
            assert!(s.centroid().length() < 1e-6 * r);
        }
    }
    // The thesis's 134-vertex sphere "of 3.9 cm³" has r = 1.
    let thesis = uv_sphere(12, 11, 1.0).unwrap().signed_volume().unwrap();
    assert!((thesis - 3.93).abs() < 0.005, "{thesis}");
}

#[test]
fn signed_volume_is_translation_invariant_and_flips_with_the_winding() {
    let s = uv_sphere(32, 31, 1.0).unwrap();
    let v = s.signed_volume().unwrap();
    for shift in [
        Vec3::new(100.0, -200.0, 50.0),
        Vec3::splat(1e4),
        Vec3::new(-3.5, 0.0, 0.25),
    ] {
        let moved: Vec<Vec3> = s.positions().iter().map(|&p| p + shift).collect();
        let moved = s.with_positions(moved).unwrap();
        // Only the f32 rounding of the shifted coordinates changes the volume (see the rigid
        // motion property below for the bound).
        let delta = U32 * max_abs_coordinate(&moved);
        let bound = 2.0 * 3f64.sqrt() * delta * s.area() + 1e-12;
        assert!(
            (moved.signed_volume().unwrap() - v).abs() <= bound,
            "shift {shift}"
        );
    }
    let flipped = reversed(&s);
    assert_eq!(flipped.signed_volume().unwrap(), -v);
    let c = subdivided_cube(4, 2.0).unwrap();
    assert_eq!(reversed(&c).signed_volume().unwrap(), -8.0);
}

#[test]
fn volume_between_a_surface_and_itself_is_zero() {
    for m in [grid(17, 2.0).unwrap(), disc(5, 12, 1.0).unwrap()] {
        assert_eq!(volume_between(&m, &m).unwrap(), 0.0);
        // Through the general path too (a renumbered copy).
        let renumbered = renumber(&m);
        assert!(volume_between(&m, &renumbered).unwrap().abs() < 1e-15);
    }
}

/// The same surface with its vertices numbered backwards.
fn renumber(m: &TriMesh) -> TriMesh {
    let n = m.vertex_count() as u32;
    let positions = m.positions().iter().rev().copied().collect();
    let triangles = m
        .triangles()
        .iter()
        .rev()
        .map(|t| t.map(|v| n - 1 - v))
        .collect();
    TriMesh::new(positions, triangles).expect("renumbering keeps a surface valid")
}

// ---------------------------------------------------------------------------------------------
// Volume between a disc and a spherical cap.

/// Sphere radius R of the cap test (cm).
const CAP_SPHERE: f64 = 2.0;
/// Disc radius a of the cap test (cm); the cap height is h = R − √(R² − a²) ≈ 0.48.
const CAP_BASE: f32 = 1.3;

/// The flat disc and the spherical cap over it (the disc's vertices lifted to
/// `z = √(R² − r²) − (R − h)`, boundary vertices left where they are), and h.
fn disc_and_cap(radial: u32, segments: u32, sign: f64) -> (TriMesh, TriMesh, f64) {
    let base = disc(radial, segments, CAP_BASE).expect("valid disc");
    let (r_sphere, a) = (CAP_SPHERE, f64::from(CAP_BASE));
    let centre_depth = (r_sphere * r_sphere - a * a).sqrt(); // R − h
    let on_boundary = base.topology().boundary_vertex_mask(base.vertex_count());
    let lifted = base
        .positions()
        .iter()
        .zip(&on_boundary)
        .map(|(&p, &fixed)| {
            if fixed {
                return p;
            }
            let r2 = f64::from(p.x).powi(2) + f64::from(p.y).powi(2);
            let z = (r_sphere * r_sphere - r2).sqrt() - centre_depth;
            Vec3::new(p.x, p.y, (sign * z) as f32)
        })
        .collect();
    let cap = base.with_positions(lifted).expect("finite positions");
    (base, cap, r_sphere - centre_depth)
}

/// The derived bound on `V_cap − V_mesh` (see the test below) and its parts.
struct CapBound {
    base: f64,
    chord: f64,
    rounding: f64,
}

/// Bound on the discretisation error of the cap volume over `base` (its xy triangles):
/// - polygon base: `(πa² − A_polygon) · a·s/(R − h)`, `s = a(1 − cos(π/m))` the sagitta;
/// - chordal: `Σ_t A_t · M_t ℓ_t² / 6`, `M_t = R²/(R² − r_t²)^{3/2}` at the triangle's outermost
///   vertex, `ℓ_t` its longest edge;
/// - f32 rounding of the positions: `√3 · 2⁻²⁴ · max(a, h) · (A_disc + A_cap)`.
fn cap_bound(base: &TriMesh, cap: &TriMesh, h: f64, segments: u32) -> CapBound {
    let (r_sphere, a) = (CAP_SPHERE, f64::from(CAP_BASE));
    let m = f64::from(segments);
    let polygon = m / 2.0 * a * a * (2.0 * PI / m).sin();
    let sagitta = a * (1.0 - (PI / m).cos());
    let base_part = (PI * a * a - polygon) * a * sagitta / (r_sphere - h);
    let mut chord = 0.0;
    for (t, area) in base.triangle_areas().into_iter().enumerate() {
        let p = base.corners(t).map(|v| v.as_dvec3());
        let r_max_sq = p.iter().map(|v| v.x * v.x + v.y * v.y).fold(0.0, f64::max);
        let longest_sq = (p[1] - p[0])
            .length_squared()
            .max((p[2] - p[1]).length_squared())
            .max((p[0] - p[2]).length_squared());
        let hessian = r_sphere * r_sphere / (r_sphere * r_sphere - r_max_sq).powf(1.5);
        chord += area * hessian * longest_sq / 6.0;
    }
    let rounding = 3f64.sqrt() * U32 * a.max(h) * (base.area() + cap.area());
    CapBound {
        base: base_part,
        chord,
        rounding,
    }
}

/// `volume_between(disc, cap)` against the cap formula `V = πh²(3R − h)/3`.
///
/// Derivation of the bound. The mesh volume is exactly `∫∫_P z_PL dA`: the flat base is the
/// boundary polygon P (vertices on the circle of radius a) and the cap mesh is the graph of the
/// piecewise-linear interpolant `z_PL` of `z(r) = √(R² − r²) − (R − h)` on the disc's triangles.
/// So `V − V_mesh = ∫∫_{disc∖P} z dA + ∫∫_P (z − z_PL) dA`, both terms ≥ 0:
/// 1. Polygonal base. `z` is concave in r and 0 at r = a, so `z(r) ≤ (a/(R − h))·(a − r)`; in the
///    circular segments outside P, `a − r ≤ s = a(1 − cos(π/m))`. The term is at most
///    `(πa² − A_P)·a·s/(R − h)` = O(m⁻⁴).
/// 2. Chordal error. On a triangle with vertices xᵢ, Taylor expansion about x gives
///    `z_PL(x) − z(x) = ½ Σ λᵢ (xᵢ − x)ᵀ D²z(ξᵢ) (xᵢ − x)`, and `|D²z| ≤ M = R²/(R² − r²)^{3/2}`
///    (the radial curvature, the larger one, growing with r, so largest at the outermost vertex).
///    `Σ λᵢ|xᵢ − x|² = ρ² − |x − c|²` (c, ρ the circumcentre and circumradius) is at most ℓ²/3
///    for ℓ the longest edge (ρ ≤ ℓ/√3 for a non-obtuse triangle; ℓ²/4 for an obtuse one). So the
///    gap is at most `M ℓ²/6` and the term at most `Σ_t A_t M_t ℓ_t²/6` = O(ℓ²).
/// 3. The f32 positions move each coordinate by at most 2⁻²⁴·max(a, h), which changes the volume
///    by at most √3·δ·(A_disc + A_cap) either way.
///
/// So `−rounding ≤ V − V_mesh ≤ base + chord + rounding`. The chordal term dominates and is
/// second order: halving every edge (twice the rings and segments) divides the error by ≈ 4,
/// which the test also checks, so a measure that is off by any fixed fraction fails.
#[test]
fn cap_over_disc_matches_the_cap_formula_with_second_order_convergence() {
    let mut errors = Vec::new();
    for (radial, segments) in [(8, 32), (16, 64), (32, 128)] {
        let (base, cap, h) = disc_and_cap(radial, segments, 1.0);
        let exact = PI * h * h * (3.0 * CAP_SPHERE - h) / 3.0;
        let volume = volume_between(&base, &cap).unwrap();
        let bound = cap_bound(&base, &cap, h, segments);
        let error = exact - volume;
        assert!(
            error >= -bound.rounding && error <= bound.base + bound.chord + bound.rounding,
            "({radial},{segments}): V = {volume}, exact {exact}, error {error:e}, bound \
             base {:e} + chord {:e} + rounding {:e}",
            bound.base,
            bound.chord,
            bound.rounding
        );
        errors.push(error);
    }
    for pair in errors.windows(2) {
        let ratio = pair[0] / pair[1];
        assert!(
            (3.6..=4.4).contains(&ratio),
            "errors {errors:?}: ratio {ratio}"
        );
    }
}

#[test]
fn cap_pushed_below_the_disc_has_negative_volume() {
    let (base, up, _) = disc_and_cap(8, 32, 1.0);
    let (_, down, _) = disc_and_cap(8, 32, -1.0);
    let (v_up, v_down) = (
        volume_between(&base, &up).unwrap(),
        volume_between(&base, &down).unwrap(),
    );
    assert!(v_up > 0.0 && v_down < 0.0);
    assert!((v_up + v_down).abs() < 1e-12, "{v_up} {v_down}");
    // Swapping the roles swaps the sign.
    assert!((volume_between(&up, &base).unwrap() + v_up).abs() < 1e-12);
}

#[test]
fn general_path_with_renumbered_after_surface_agrees_with_the_fast_path() {
    let (base, cap, _) = disc_and_cap(8, 32, 1.0);
    let fast = volume_between(&base, &cap).unwrap();
    let general = volume_between(&base, &renumber(&cap)).unwrap();
    assert!((fast - general).abs() < 1e-13, "{fast} vs {general}");
    // A cap whose vertex numbering is rotated along the boundary ring: the loop matches with a
    // cyclic shift.
    let n = cap.vertex_count() as u32;
    let shifted = TriMesh::new(
        cap.positions()[1..]
            .iter()
            .chain(&cap.positions()[..1])
            .copied()
            .collect(),
        cap.triangles()
            .iter()
            .map(|t| t.map(|v| (v + n - 1) % n))
            .collect(),
    )
    .unwrap();
    let general = volume_between(&base, &shifted).unwrap();
    assert!((fast - general).abs() < 1e-13);
}

#[test]
fn moved_boundary_vertex_is_a_boundary_mismatch_naming_it() {
    let (base, cap, _) = disc_and_cap(4, 16, 1.0);
    let boundary_vertex = base.topology().boundary_loops()[0][3];
    let mut p = cap.positions().to_vec();
    p[boundary_vertex as usize].z += 1e-3;
    let moved = cap.with_positions(p).unwrap();
    match volume_between(&base, &moved) {
        Err(MeshError::BoundaryMismatch { reason }) => {
            assert!(
                reason.contains(&format!("boundary vertex {boundary_vertex} ")),
                "{reason}"
            );
        }
        other => panic!("expected a boundary mismatch, got {other:?}"),
    }
    // A move below the tolerance is welded away: the volume does not change.
    let mut p = cap.positions().to_vec();
    p[boundary_vertex as usize].z += 1e-7;
    let nudged = cap.with_positions(p).unwrap();
    assert_eq!(
        volume_between(&base, &nudged).unwrap(),
        volume_between(&base, &cap).unwrap()
    );
    // Through the general path the message names the loop and the vertices that differ.
    let mut p = cap.positions().to_vec();
    p[boundary_vertex as usize].x += 1e-2;
    let moved = renumber(&cap.with_positions(p).unwrap());
    match volume_between(&base, &moved) {
        Err(MeshError::BoundaryMismatch { reason }) => {
            assert!(reason.contains("before's boundary loop 0"), "{reason}");
            assert!(
                reason.contains(&format!("vertex {boundary_vertex} ")),
                "{reason}"
            );
        }
        other => panic!("expected a boundary mismatch, got {other:?}"),
    }
}

#[test]
fn other_boundary_mismatches_are_explained() {
    let small = disc(3, 12, 1.0).unwrap();
    let finer = disc(3, 16, 1.0).unwrap();
    let err = volume_between(&small, &finer).unwrap_err();
    assert!(
        matches!(&err, MeshError::BoundaryMismatch { reason } if reason.contains("length")),
        "{err}"
    );
    let larger = renumber(&disc(3, 12, 1.5).unwrap());
    let err = volume_between(&small, &larger).unwrap_err();
    assert!(
        matches!(&err, MeshError::BoundaryMismatch { reason } if reason.contains("no boundary vertex of after")),
        "{err}"
    );
    let flipped = renumber(&reversed(&small));
    let err = volume_between(&small, &flipped).unwrap_err();
    assert!(
        matches!(&err, MeshError::BoundaryMismatch { reason } if reason.contains("opposite direction")),
        "{err}"
    );
    // An annulus-like grid with a hole has two loops; a disc has one.
    let plane = grid(4, 1.0).unwrap();
    let (p, t) = plane.clone().into_parts();
    let holed = TriMesh::new(
        p,
        t.into_iter()
            .filter(|t| !t.contains(&5) || !t.contains(&10))
            .collect(),
    )
    .unwrap();
    assert_eq!(holed.topology().boundary_loops().len(), 2);
    let err = volume_between(&plane, &holed).unwrap_err();
    assert!(
        matches!(&err, MeshError::BoundaryMismatch { reason } if reason.contains("before has 1 boundary loops, after has 2")),
        "{err}"
    );
    let sphere = uv_sphere(8, 7, 1.0).unwrap();
    assert_eq!(
        volume_between(&sphere, &plane),
        Err(MeshError::NotOpen { surface: "before" })
    );
}

// ---------------------------------------------------------------------------------------------
// Rigid motions.

fn rigid_motion() -> impl Strategy<Value = (DQuat, DVec3)> {
    (
        (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
        0.0f64..(2.0 * PI),
        (-10.0f64..10.0, -10.0f64..10.0, -10.0f64..10.0),
    )
        .prop_map(|((x, y, z), angle, (tx, ty, tz))| {
            let axis = DVec3::new(x, y, z).try_normalize().unwrap_or(DVec3::Z);
            (DQuat::from_axis_angle(axis, angle), DVec3::new(tx, ty, tz))
        })
}

/// Moves every vertex (in f64, then rounded to f32 once).
fn moved(m: &TriMesh, (q, t): (DQuat, DVec3)) -> TriMesh {
    let p = m
        .positions()
        .iter()
        .map(|p| (q * p.as_dvec3() + t).as_vec3())
        .collect();
    m.with_positions(p).expect("finite positions")
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

    /// Only the f32 rounding of the moved coordinates (≤ 2⁻²⁴·max|x| each) changes the measures:
    /// by at most √3·δ·Σ P_t/2 (area) and √3·δ·A (volume), first order; twice that is allowed.
    #[test]
    fn rigid_motions_keep_area_volume_and_volume_between(motion in rigid_motion()) {
        let sqrt3 = 3f64.sqrt();
        for shape in [uv_sphere(12, 11, 1.0).unwrap(), subdivided_cube(3, 2.0).unwrap()] {
            let m = moved(&shape, motion);
            let delta = U32 * max_abs_coordinate(&m);
            let area_bound = 2.0 * sqrt3 * delta * half_perimeter_sum(&shape) + 1e-12;
            prop_assert!((m.area() - shape.area()).abs() <= area_bound);
            let volume_bound = 2.0 * sqrt3 * delta * shape.area() + 1e-12;
            let (v0, v1) = (shape.signed_volume().unwrap(), m.signed_volume().unwrap());
            prop_assert!((v1 - v0).abs() <= volume_bound, "{} vs {}", v1, v0);
        }
        let (base, cap, _) = disc_and_cap(6, 24, 1.0);
        let v0 = volume_between(&base, &cap).unwrap();
        let (base_m, cap_m) = (moved(&base, motion), moved(&cap, motion));
        let delta = U32 * max_abs_coordinate(&cap_m).max(max_abs_coordinate(&base_m));
        let bound = 2.0 * sqrt3 * delta * (base.area() + cap.area()) + 1e-12;
        let v1 = volume_between(&base_m, &cap_m).unwrap();
        prop_assert!((v1 - v0).abs() <= bound, "{} vs {}", v1, v0);
    }
}
