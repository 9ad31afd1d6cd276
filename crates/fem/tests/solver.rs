//! The solver itself: it meets its tolerance, a tighter tolerance does not move the answer,
//! load steps reach the same equilibrium, and bad input is an error, not a panic.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::print_stdout)]

mod common;

use glam::{DVec3, Vec3};
use tissue_fem::{ElasticMaterial, FemError, Plane, SolverSettings, SphereIndenter, StaticProblem};

fn material() -> ElasticMaterial {
    ElasticMaterial {
        young_kpa: 500.0,
        poisson: 0.4,
        density: 1.0,
    }
}

/// A soft cantilever sagging visibly (large deflection, geometric nonlinearity), 40 × 4 × 4
/// cells of 10 × 1 × 1 cm.
fn sagging_beam() -> (StaticProblem, Vec<u32>) {
    let mesh = tissue_mesh::tet_box(40, 4, 4, Vec3::new(10.0, 1.0, 1.0)).unwrap();
    let mut problem = StaticProblem::new(&mesh, material()).unwrap();
    problem.clamp_where(|p| p.x < -5.0 + 1e-6);
    let tip = problem.nodes_where(|p| p.x > 5.0 - 1e-6);
    (problem, tip)
}

#[test]
fn the_residual_meets_the_tolerance_and_a_tighter_one_does_not_move_the_answer() {
    let (mut problem, tip) = sagging_beam();
    let loose = problem.solve().unwrap();
    let r = loose.report;
    assert!(r.converged, "{r:?}");
    assert!(r.residual <= r.tolerance * r.force_scale, "{r:?}");
    assert!(r.relative_residual <= 1e-8);
    let tip_loose = loose.mean_displacement(&tip);
    problem
        .set_settings(SolverSettings {
            residual_tolerance: 1e-9,
            ..SolverSettings::default()
        })
        .unwrap();
    let tight = problem.solve().unwrap();
    assert!(tight.report.converged);
    assert!(tight.report.relative_residual <= 1e-9);
    let tip_tight = tight.mean_displacement(&tip);
    let change = (tip_tight - tip_loose).length() / tip_tight.length();
    println!(
        "solver: tip sag {:.4} cm (L = 10 cm), {} iterations at 1e-8 (relative residual {:.1e}), \
         {} at 1e-9 ({:.1e}); tip moved by {change:.1e} of itself",
        -tip_tight.z,
        r.iterations,
        r.relative_residual,
        tight.report.iterations,
        tight.report.relative_residual
    );
    assert!(
        -tip_tight.z > 1.0,
        "the beam should sag visibly: {tip_tight}"
    );
    assert!(change < 1e-3, "{change}");
}

#[test]
fn load_steps_reach_the_same_equilibrium() {
    let (mut problem, tip) = sagging_beam();
    let one = problem.solve().unwrap().mean_displacement(&tip);
    problem
        .set_settings(SolverSettings {
            load_steps: 4,
            ..SolverSettings::default()
        })
        .unwrap();
    let stepped = problem.solve().unwrap();
    assert!(stepped.report.converged);
    assert_eq!(stepped.report.load_steps, 4);
    let four = stepped.mean_displacement(&tip);
    assert!(
        (four - one).length() < 1e-6 * one.length(),
        "{one} vs {four}"
    );
}

#[test]
fn an_indenter_on_a_block_on_the_floor_balances() {
    // A sphere pressed into a soft block resting on the floor under gravity: floor = weight +
    // indenter force.
    let mesh = tissue_mesh::tet_box(6, 6, 3, Vec3::new(3.0, 3.0, 1.5)).unwrap();
    let mut problem = StaticProblem::new(&mesh, material()).unwrap();
    problem.set_floor(Plane::floor(-0.75)).unwrap();
    for n in problem.nodes_where(|p| p.z < -0.75 + 1e-6 && p.y < -1.5 + 1e-6) {
        problem.fix_axes(n, [true, true, false]).unwrap();
    }
    problem
        .set_indenter(SphereIndenter {
            contact: DVec3::new(0.0, 0.0, 0.75),
            direction: -DVec3::Z,
            radius: 1.0,
            depth: 0.2,
        })
        .unwrap();
    let s = problem.solve().unwrap();
    assert!(s.report.converged, "{:?}", s.report);
    assert!(s.indenter_force.z < 0.0);
    let balance = s.floor_force + s.indenter_force + s.weight + s.clamp_force;
    assert!(balance.length() < 1e-6 * s.floor_force.z, "{balance}");
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let mesh = tissue_mesh::tet_box(2, 2, 2, Vec3::ONE).unwrap();
    let bad = ElasticMaterial {
        poisson: 0.6,
        ..material()
    };
    assert!(matches!(
        StaticProblem::new(&mesh, bad),
        Err(FemError::Material { .. })
    ));
    let mut problem = StaticProblem::new(&mesh, material()).unwrap();
    assert!(matches!(problem.clamp(1000), Err(FemError::Problem { .. })));
    assert!(problem.clamp_at(0, DVec3::NAN).is_err());
    assert!(problem.fix_axes(27, [true; 3]).is_err());
    assert!(problem.set_gravity(DVec3::INFINITY).is_err());
    assert!(problem
        .set_floor(Plane {
            point: DVec3::ZERO,
            normal: DVec3::ZERO
        })
        .is_err());
    let sphere = SphereIndenter {
        contact: DVec3::ZERO,
        direction: -DVec3::Z,
        radius: 1.0,
        depth: 0.1,
    };
    assert!(problem
        .set_indenter(SphereIndenter {
            radius: -1.0,
            ..sphere
        })
        .is_err());
    assert!(problem
        .set_indenter(SphereIndenter {
            depth: f64::NAN,
            ..sphere
        })
        .is_err());
    for settings in [
        SolverSettings {
            residual_tolerance: 0.0,
            ..SolverSettings::default()
        },
        SolverSettings {
            load_steps: 0,
            ..SolverSettings::default()
        },
        SolverSettings {
            contact_stiffness: f64::NAN,
            ..SolverSettings::default()
        },
    ] {
        let err = problem.set_settings(settings).unwrap_err();
        assert!(err.to_string().contains("give"), "{err}");
    }
    // A body held by nothing, falling under gravity: no equilibrium. An error or an
    // unconverged report, never a panic.
    problem
        .set_settings(SolverSettings {
            max_iterations: 5,
            ..SolverSettings::default()
        })
        .unwrap();
    match problem.solve() {
        Ok(s) => assert!(!s.report.converged),
        Err(e) => assert!(matches!(e, FemError::Factorisation { .. }), "{e}"),
    }
}
