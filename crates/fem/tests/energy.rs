//! The stable neo-Hookean element against central finite differences, at rest and against
//! Hooke's law at small strain.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)]

use glam::{DMat3, DVec3};
use tissue_fem::{project_psd, ElasticMaterial, FemError, StableNeoHookean, TetElement};

fn material(poisson: f64) -> ElasticMaterial {
    ElasticMaterial {
        young_kpa: 20.0,
        poisson,
        density: 1.05,
    }
}

fn rest() -> [DVec3; 4] {
    [
        DVec3::new(0.1, -0.2, 0.05),
        DVec3::new(1.2, 0.1, -0.1),
        DVec3::new(0.3, 1.1, 0.2),
        DVec3::new(0.2, 0.3, 0.9),
    ]
}

/// A deterministic, fairly large deformation (stretch, shear, some compression).
fn deformed() -> [DVec3; 4] {
    let f = DMat3::from_cols(
        DVec3::new(1.3, 0.2, -0.1),
        DVec3::new(-0.15, 0.8, 0.25),
        DVec3::new(0.1, -0.3, 0.9),
    );
    rest().map(|x| f * x + DVec3::new(0.3, -0.7, 0.2))
}

#[test]
fn gradient_matches_central_differences() {
    for nu in [0.0, 0.3, 0.45] {
        let model = StableNeoHookean::new(&material(nu));
        let e = TetElement::new(rest()).unwrap();
        let x = deformed();
        let g = e.gradient(&model, &x);
        let h = 1e-6;
        let scale = g.iter().map(|v| v.abs().max_element()).fold(0.0, f64::max);
        for a in 0..4 {
            for i in 0..3 {
                let (mut xp, mut xm) = (x, x);
                xp[a][i] += h;
                xm[a][i] -= h;
                let fd = (e.energy(&model, &xp) - e.energy(&model, &xm)) / (2.0 * h);
                assert!(
                    (fd - g[a][i]).abs() <= 1e-6 * scale,
                    "ν {nu}: node {a} axis {i}: analytic {} fd {fd}",
                    g[a][i]
                );
            }
        }
    }
}

#[test]
fn hessian_matches_central_differences_of_the_gradient() {
    for nu in [0.0, 0.3, 0.45] {
        let model = StableNeoHookean::new(&material(nu));
        let e = TetElement::new(rest()).unwrap();
        let x = deformed();
        let k = e.hessian(&model, &x, false);
        let scale = k.iter().flatten().map(|v| v.abs()).fold(0.0, f64::max);
        let h = 1e-6;
        for b in 0..4 {
            for j in 0..3 {
                let (mut xp, mut xm) = (x, x);
                xp[b][j] += h;
                xm[b][j] -= h;
                let (gp, gm) = (e.gradient(&model, &xp), e.gradient(&model, &xm));
                for a in 0..4 {
                    for i in 0..3 {
                        let fd = (gp[a][i] - gm[a][i]) / (2.0 * h);
                        let an = k[3 * a + i][3 * b + j];
                        assert!(
                            (fd - an).abs() <= 1e-6 * scale,
                            "ν {nu}: ({a},{i})×({b},{j}): analytic {an} fd {fd}"
                        );
                    }
                }
            }
        }
        // Symmetric.
        for r in 0..12 {
            for c in 0..12 {
                assert!((k[r][c] - k[c][r]).abs() <= 1e-12 * scale);
            }
        }
    }
}

#[test]
fn the_density_hessian_matches_differences_of_the_stress() {
    let model = StableNeoHookean::new(&material(0.3));
    let f = DMat3::from_cols(
        DVec3::new(0.7, 0.2, -0.1),
        DVec3::new(-0.15, 0.6, 0.25),
        DVec3::new(0.1, -0.3, -0.4), // inverted: J < 0
    );
    assert!(f.determinant() < 0.0);
    let h = model.hessian_density(&f);
    let step = 1e-6;
    for c in 0..9 {
        let mut fp = f.to_cols_array();
        let mut fm = fp;
        fp[c] += step;
        fm[c] -= step;
        let pp = model
            .first_piola(&DMat3::from_cols_array(&fp))
            .to_cols_array();
        let pm = model
            .first_piola(&DMat3::from_cols_array(&fm))
            .to_cols_array();
        for r in 0..9 {
            let fd = (pp[r] - pm[r]) / (2.0 * step);
            assert!(
                (fd - h[r][c]).abs() < 1e-6 * model.lambda.max(model.mu),
                "{r},{c}"
            );
        }
    }
}

#[test]
fn the_projected_hessian_is_psd_and_unchanged_when_already_psd() {
    let model = StableNeoHookean::new(&material(0.3));
    let e = TetElement::new(rest()).unwrap();
    // Strong compression makes the raw Hessian indefinite.
    let x = rest().map(|p| p * 0.4);
    let mut raw = model.hessian_density(&e.deformation_gradient(&x));
    let projected_something = project_psd(&mut raw);
    assert!(
        projected_something,
        "expected an indefinite Hessian under compression"
    );
    let k = e.hessian(&model, &x, true);
    // xᵀ K x ≥ 0 for a few deterministic vectors.
    for s in 0..50 {
        let v: Vec<f64> = (0..12)
            .map(|i| ((i * 7 + s * 13) as f64 * 0.731).sin())
            .collect();
        let mut q = 0.0;
        for r in 0..12 {
            for c in 0..12 {
                q += v[r] * k[r][c] * v[c];
            }
        }
        assert!(q >= -1e-9 * model.mu, "vᵀKv = {q}");
    }
    // At rest the Hessian is PSD already (linear elasticity), so projection leaves it.
    let mut at_rest = model.hessian_density(&DMat3::IDENTITY);
    let before = at_rest;
    project_psd(&mut at_rest);
    assert_eq!(before, at_rest);
}

#[test]
fn energy_and_stress_vanish_at_rest_and_under_rotation() {
    for nu in [0.0, 0.25, 0.49] {
        let model = StableNeoHookean::new(&material(nu));
        let e = TetElement::new(rest()).unwrap();
        assert!(model.energy_density(&DMat3::IDENTITY).abs() < 1e-9 * model.mu);
        let p = model.first_piola(&DMat3::IDENTITY);
        assert!(
            p.abs().to_cols_array().iter().all(|&v| v < 1e-9 * model.mu),
            "{p}"
        );
        // A rigid motion.
        let r = DMat3::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 0.9);
        let x = rest().map(|p| r * p + DVec3::new(3.0, -1.0, 2.0));
        assert!(e.energy(&model, &x).abs() < 1e-9 * model.mu * e.volume);
        let g = e.gradient(&model, &x);
        assert!(g.iter().all(|v| v.length() < 1e-9 * model.mu));
    }
}

#[test]
fn the_small_strain_stress_is_hookes_law() {
    for nu in [0.0, 0.3, 0.45] {
        let m = material(nu);
        let (mu, lambda) = m.lame();
        let model = StableNeoHookean::new(&m);
        let eps = 1e-6;
        // A general symmetric strain.
        let strain = DMat3::from_cols(
            DVec3::new(1.0, 0.3, -0.2),
            DVec3::new(0.3, -0.5, 0.4),
            DVec3::new(-0.2, 0.4, 0.8),
        ) * eps;
        let sigma = model.cauchy(&(DMat3::IDENTITY + strain));
        let hooke = strain * (2.0 * mu)
            + DMat3::IDENTITY * (lambda * (strain.x_axis.x + strain.y_axis.y + strain.z_axis.z));
        let err = (sigma - hooke)
            .abs()
            .to_cols_array()
            .iter()
            .fold(0.0f64, |a, &b| a.max(b));
        let size = hooke
            .abs()
            .to_cols_array()
            .iter()
            .fold(0.0f64, |a, &b| a.max(b));
        assert!(err < 1e-4 * size, "ν {nu}: σ {sigma} vs Hooke {hooke}");
        // Uniaxial stress: free lateral contraction −ν ε gives σ_xx = E ε and nothing else.
        let lateral = -nu * eps;
        let f = DMat3::from_diagonal(DVec3::new(1.0 + eps, 1.0 + lateral, 1.0 + lateral));
        let s = model.cauchy(&f);
        let e_mod = m.young();
        assert!(
            (s.x_axis.x - e_mod * eps).abs() < 1e-4 * e_mod * eps,
            "ν {nu}: {s}"
        );
        assert!(s.y_axis.y.abs() < 1e-4 * e_mod * eps && s.z_axis.z.abs() < 1e-4 * e_mod * eps);
    }
}

#[test]
fn bad_materials_say_what_and_how() {
    let ok = material(0.3);
    assert!(ok.validate().is_ok());
    for bad in [
        ElasticMaterial {
            young_kpa: 0.0,
            ..ok
        },
        ElasticMaterial {
            young_kpa: f64::NAN,
            ..ok
        },
        ElasticMaterial { poisson: 0.5, ..ok },
        ElasticMaterial {
            poisson: -0.1,
            ..ok
        },
        ElasticMaterial { density: 0.0, ..ok },
        ElasticMaterial {
            density: f64::INFINITY,
            ..ok
        },
    ] {
        let err = bad.validate().unwrap_err();
        assert!(matches!(err, FemError::Material { .. }));
        assert!(err.to_string().contains("give"), "{err}");
    }
    let (mu, lambda) = ok.lame();
    assert!((mu - 20.0e4 / 2.6).abs() < 1e-6 * mu);
    assert!((lambda - 20.0e4 * 0.3 / (1.3 * 0.4)).abs() < 1e-6 * lambda);
    assert_eq!(material(0.0).lame().1, 0.0);
    assert!(
        TetElement::new([DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0)]).is_none()
    );
}
