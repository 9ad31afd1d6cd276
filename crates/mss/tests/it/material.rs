//! Van Gelder stiffness (eq. 3) against hand computation; masses (eqs. 1, 2) sum to the total.
#![allow(clippy::unwrap_used)]

use glam::Vec3;
use tissue_mesh::{grid, tet_box, TriMesh};
use tissue_mss::{masses_from_tets, masses_from_triangles, springs_from_triangles, SheetMaterial};

const MATERIAL: SheetMaterial = SheetMaterial {
    young: 1000.0,
    poisson: 0.3,
    thickness: 0.1,
};

fn close(a: f32, b: f64, what: &str) {
    assert!(
        (f64::from(a) - b).abs() <= 1e-5 * b.abs(),
        "{what}: {a} vs hand value {b}"
    );
}

fn stiffness_of(springs: &[tissue_mss::Spring], a: u32, b: u32) -> f32 {
    springs
        .iter()
        .find(|s| (s.a, s.b) == (a.min(b), a.max(b)))
        .map(|s| s.k)
        .unwrap()
}

#[test]
fn equilateral_triangle_matches_hand_computation() {
    // Side 2, area √3. E₂ = E·t = 100. For every side:
    //   E₂/(1+ν)·2A/c² = 100/1.3 · 2√3/4 = 66.61734...
    //   E₂ν/(1−ν²)·(a²+b²−c²)/(4A) = 30/0.91 · 4/(4√3) = 19.03352...
    // k = 85.650864...
    let h = 3f32.sqrt();
    let mesh = TriMesh::new(
        vec![Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(1.0, h, 0.0)],
        vec![[0, 1, 2]],
    )
    .unwrap();
    let springs = springs_from_triangles(&mesh, &MATERIAL, 0).unwrap();
    assert_eq!(springs.len(), 3);
    for s in &springs {
        close(s.k, 85.650_864_110_548_87, "equilateral side");
        close(s.rest, 2.0, "rest length");
    }
}

#[test]
fn right_triangle_matches_hand_computation() {
    // Legs 3 (0–1) and 4 (0–2), hypotenuse 5 (1–2), area 6.
    //   hypotenuse: 100/1.3 · 12/25 + 30/0.91 · (9+16−25)/24 = 36.923077 (right angle: no ν term)
    //   leg 3:      100/1.3 · 12/9  + 30/0.91 · (16+25−9)/24 = 146.520147
    //   leg 4:      100/1.3 · 12/16 + 30/0.91 · (9+25−16)/24 = 82.417582
    let mesh = TriMesh::new(
        vec![
            Vec3::ZERO,
            Vec3::new(3.0, 0.0, 0.0),
            Vec3::new(0.0, 4.0, 0.0),
        ],
        vec![[0, 1, 2]],
    )
    .unwrap();
    let springs = springs_from_triangles(&mesh, &MATERIAL, 10).unwrap();
    close(stiffness_of(&springs, 11, 12), 36.923_076_923, "hypotenuse");
    close(stiffness_of(&springs, 10, 11), 146.520_146_520, "leg 3");
    close(stiffness_of(&springs, 10, 12), 82.417_582_417, "leg 4");
}

#[test]
fn shared_edge_sums_both_triangles() {
    // Unit square split along 0–2: the diagonal belongs to two right isosceles triangles, each
    // giving 100/1.3 · 2·0.5/2 + 0 = 38.461538; the sum is 76.923077.
    let mesh = TriMesh::new(
        vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
        vec![[0, 1, 2], [0, 2, 3]],
    )
    .unwrap();
    let springs = springs_from_triangles(&mesh, &MATERIAL, 0).unwrap();
    assert_eq!(springs.len(), 5);
    close(stiffness_of(&springs, 0, 2), 76.923_076_923, "diagonal");
    // A leg: 100/1.3 · 1/1 + 30/0.91 · (1+2−1)/(4·0.5) = 76.923077 + 32.967033 = 109.890110.
    close(stiffness_of(&springs, 0, 1), 109.890_109_890, "side");
}

#[test]
fn bad_material_is_an_error() {
    let mesh = grid(3, 1.0).unwrap();
    for m in [
        SheetMaterial {
            young: -1.0,
            ..MATERIAL
        },
        SheetMaterial {
            poisson: 0.5,
            ..MATERIAL
        },
        SheetMaterial {
            thickness: f64::NAN,
            ..MATERIAL
        },
    ] {
        assert!(springs_from_triangles(&mesh, &m, 0).is_err());
    }
}

#[test]
fn triangle_masses_sum_to_the_total_and_follow_area() {
    let mesh = grid(65, 20.0).unwrap();
    let total = mesh.area() * 0.2 * 1.1; // area × thickness × density
    let m = masses_from_triangles(&mesh, total).unwrap();
    let sum: f64 = m.iter().map(|&x| f64::from(x)).sum();
    assert!((sum - total).abs() < 1e-5 * total, "{sum} vs {total}");
    // One interior vertex by eq. (2): a third of its triangles' share of the mass.
    let v = 65 * 32 + 32;
    let around: f64 = mesh
        .topology()
        .vertex_triangles(v)
        .iter()
        .map(|&t| mesh.triangle_areas()[t as usize])
        .sum();
    let expected = total * around / (3.0 * mesh.area());
    assert!((f64::from(m[v as usize]) - expected).abs() < 1e-6 * expected);
}

#[test]
fn tet_masses_sum_to_the_total() {
    let mesh = tet_box(4, 3, 2, Vec3::new(2.0, 1.5, 1.0)).unwrap();
    let total = mesh.volume() * 1.05;
    let m = masses_from_tets(&mesh, total).unwrap();
    let sum: f64 = m.iter().map(|&x| f64::from(x)).sum();
    assert!((sum - total).abs() < 1e-5 * total, "{sum} vs {total}");
    assert!(masses_from_tets(&mesh, 0.0).is_err());
}

#[test]
fn floored_springs_keep_the_shear_term_where_eq_3_turns_negative() {
    use tissue_mss::springs_from_triangles_floored;
    // One very obtuse triangle (170° at the apex): with ν = 0.45 the long side's eq. (3) sum is
    // negative, so the strict builder refuses it and the floored one keeps E₂/(1+ν)·2A/c².
    let apex = 85f64.to_radians();
    let mesh = tissue_mesh::TriMesh::new(
        vec![
            glam::Vec3::new(-apex.sin() as f32, 0.0, 0.0),
            glam::Vec3::new(apex.sin() as f32, 0.0, 0.0),
            glam::Vec3::new(0.0, apex.cos() as f32, 0.0),
        ],
        vec![[0, 1, 2]],
    )
    .unwrap();
    let material = tissue_mss::SheetMaterial {
        young: 1.0e6,
        poisson: 0.45,
        thickness: 0.1,
    };
    assert!(matches!(
        tissue_mss::springs_from_triangles(&mesh, &material, 0),
        Err(tissue_mss::MssError::InvalidSpring { .. })
    ));
    let (springs, replaced) = springs_from_triangles_floored(&mesh, &material, 0).unwrap();
    assert_eq!(replaced.len(), 1);
    let long = springs
        .iter()
        .find(|s| (s.a, s.b) == (0, 1))
        .expect("the long side's spring");
    let c = 2.0 * apex.sin();
    let area = 0.5 * c * apex.cos();
    let expected = 1.0e6 * 0.1 / 1.45 * (2.0 * area / (c * c));
    assert!(
        (f64::from(long.k) - expected).abs() < 1e-4 * expected,
        "{} vs {expected}",
        long.k
    );
    // The other two sides keep eq. (3) exactly, as the strict builder gives them.
    for s in springs.iter().filter(|s| (s.a, s.b) != (0, 1)) {
        let (a, b, cc) = (c, 1.0, 1.0);
        let k = tissue_mss::van_gelder(a, b, cc, area, &material);
        assert!((f64::from(s.k) - k).abs() < 1e-4 * k, "{} vs {k}", s.k);
    }
}
