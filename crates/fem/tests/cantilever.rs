//! A slender cantilever under its own weight against Euler–Bernoulli, and the physical scaling
//! of its deflection with E and ρ.
//!
//! Beam: square section H × H = 1 × 1 cm, length L = 20 cm (L/H = 20), clamped at x = 0, ρ g
//! along −z. Beam theory: tip deflection δ = q L⁴ / (8 E I), q = ρ g H², I = H⁴/12. With
//! E = 10⁵ kPa and ρ = 1 g/cm³, δ = 0.235 cm = 1.2 % of L: small deflection (the geometric
//! nonlinearity changes δ by about (δ/L)² ≈ 10⁻⁴). ν = 0: Euler–Bernoulli is then exact for
//! the slender limit (no anticlastic bending) and linear tetrahedra lock least; the shear
//! (Timoshenko) correction E/(3kG)·(H/L)² is 0.2 %.
//!
//! Mesh: `common::lattice_block`, Kuhn tetrahedra mirrored cell by cell. Measured (tip mean
//! over the end face, ratio to beam theory): linear tetrahedra are stiff in bending with an
//! error of about 1.9·(h_z/H)² once the cells along the beam are short enough (h_x ≤ h_z/2); the
//! cells across the width barely matter at ν = 0 (2 or 6 across: 0.927 against 0.926 at
//! h_z = H/6). Plain `tet_box` (Kuhn cells all alike) at 400 × 2 × 10: −1.95 % (mirrored
//! −1.88 %); at ν = 0.3 the mirrored 400 × 4 × 10 mesh is −3.1 % (volumetric and Poisson
//! stiffening).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::print_stdout)]

mod common;

use std::time::Instant;

use tissue_fem::{ElasticMaterial, StaticProblem, GRAVITY};

const L: f64 = 20.0;
const H: f64 = 1.0;

fn material() -> ElasticMaterial {
    ElasticMaterial {
        young_kpa: 1.0e5,
        poisson: 0.0,
        density: 1.0,
    }
}

/// Tip deflection (cm, positive down) of the beam on `nx × ny × nz` cells, and the report.
fn tip_deflection(
    material: ElasticMaterial,
    nx: usize,
    ny: usize,
    nz: usize,
) -> (f64, tissue_fem::StaticSolution) {
    let mesh = common::lattice_block(
        &common::uniform(0.0, L, nx),
        &common::uniform(-H / 2.0, H / 2.0, ny),
        &common::uniform(-H / 2.0, H / 2.0, nz),
        true,
    );
    let mut problem = StaticProblem::new(&mesh, material).unwrap();
    let clamped = problem.clamp_where(|p| p.x < 1e-9);
    assert_eq!(clamped, (ny + 1) * (nz + 1));
    let tip = problem.nodes_where(|p| p.x > L - 1e-9);
    let solution = problem.solve().unwrap();
    assert!(solution.report.converged, "{:?}", solution.report);
    (-solution.mean_displacement(&tip).z, solution)
}

fn beam_theory(material: ElasticMaterial) -> f64 {
    let q = material.density * GRAVITY * H * H;
    let i = H.powi(4) / 12.0;
    q * L.powi(4) / (8.0 * material.young() * i)
}

#[test]
fn cantilever_under_its_own_weight_meets_euler_bernoulli_within_3_percent() {
    let m = material();
    let beam = beam_theory(m);
    let mut errors = Vec::new();
    // (nx, ny, nz): cells 0.083 × 0.5 × 0.167 cm, 0.0625 × 0.5 × 0.125 cm, 0.05 × 0.5 × 0.1 cm.
    for (nx, ny, nz) in [(240, 2, 6), (320, 2, 8), (400, 2, 10)] {
        let start = Instant::now();
        let (tip, solution) = tip_deflection(m, nx, ny, nz);
        let error = (tip - beam) / beam;
        println!(
            "cantilever {nx}×{ny}×{nz} cells ({} tets): tip {tip:.5} cm, beam {beam:.5} cm, \
             error {:+.2} %, {} Newton iterations, relative residual {:.1e}, {:.2} s",
            6 * nx * ny * nz,
            100.0 * error,
            solution.report.iterations,
            solution.report.relative_residual,
            start.elapsed().as_secs_f64()
        );
        // The clamp carries the weight.
        let weight = m.density * GRAVITY * L * H * H;
        assert!((solution.clamp_force.z - weight).abs() < 1e-6 * weight);
        errors.push(error);
    }
    // Linear tetrahedra are stiffer than the beam, and the error shrinks with the cells
    // through the thickness, about as (h_z/H)²: (6/10)² = 0.36.
    assert!(errors.iter().all(|&e| e < 0.0), "{errors:?}");
    assert!(
        errors[0] < errors[1] && errors[1] < errors[2],
        "not converging: {errors:?}"
    );
    assert!(
        errors[2].abs() < 0.03,
        "10 cells through the thickness: {errors:?}"
    );
    assert!(
        errors[0].abs() > 0.03,
        "the coarse mesh was expected to be visibly stiff"
    );
    let ratio = errors[2] / errors[0];
    assert!((0.25..0.5).contains(&ratio), "error ratio {ratio}");
}

#[test]
fn twice_e_halves_and_twice_rho_doubles_the_deflection() {
    let m = material();
    let (nx, ny, nz) = (80, 2, 4);
    let (base, _) = tip_deflection(m, nx, ny, nz);
    let stiffer = ElasticMaterial {
        young_kpa: 2.0 * m.young_kpa,
        ..m
    };
    let (stiff, _) = tip_deflection(stiffer, nx, ny, nz);
    let heavier = ElasticMaterial {
        density: 2.0 * m.density,
        ..m
    };
    let (heavy, _) = tip_deflection(heavier, nx, ny, nz);
    println!(
        "scaling ({nx}×{ny}×{nz}): δ(2E)/δ(E) = {:.5}, δ(2ρ)/δ(ρ) = {:.5}",
        stiff / base,
        heavy / base
    );
    assert!((0.45..=0.55).contains(&(stiff / base)), "{}", stiff / base);
    assert!((1.9..=2.1).contains(&(heavy / base)), "{}", heavy / base);
    // Small deflection: the response is linear to well under 1 %.
    assert!((stiff / base - 0.5).abs() < 0.005 && (heavy / base - 2.0).abs() < 0.01);
}
