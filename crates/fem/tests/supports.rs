//! Balance on the supports: a block on the floor carries its weight into the floor; a block
//! squeezed between the floor and a plate is in uniaxial stress; a bar stretched by prescribed
//! end positions pulls back with E A ε.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::print_stdout)]

mod common;

use glam::{DVec3, Vec3};
use tissue_fem::{ElasticMaterial, Plane, Plate, StaticProblem, GRAVITY};

fn tissue() -> ElasticMaterial {
    ElasticMaterial {
        young_kpa: 10.0,
        poisson: 0.45,
        density: 1.05,
    }
}

/// Takes out the rigid motions a frictionless floor allows (sliding in x, y, turning about z)
/// and nothing else: the bottom centre is held in x and y, the bottom node at `(dx, 0)` from it
/// in y; both stay free vertically. By symmetry neither carries a force, so the block can still
/// spread sideways freely.
fn hold_sideways(problem: &mut StaticProblem, bottom: f64, dx: f64) {
    let at = |problem: &StaticProblem, x: f64| {
        let nodes = problem.nodes_where(|p| {
            (p.z - bottom).abs() < 1e-6 && (p.x - x).abs() < 1e-6 && p.y.abs() < 1e-6
        });
        assert_eq!(nodes.len(), 1);
        nodes[0]
    };
    let centre = at(problem, 0.0);
    let side = at(problem, dx);
    problem.fix_axes(centre, [true, true, false]).unwrap();
    problem.fix_axes(side, [false, true, false]).unwrap();
}

#[test]
fn a_block_on_the_floor_puts_its_weight_on_the_floor() {
    // 4 × 4 × 2 cm of soft tissue (10 kPa, ν = 0.45), 8 × 8 × 4 cells of tet_box.
    let size = Vec3::new(4.0, 4.0, 2.0);
    let mesh = tissue_mesh::tet_box(8, 8, 4, size).unwrap();
    let m = tissue();
    let mut problem = StaticProblem::new(&mesh, m).unwrap();
    problem.set_floor(Plane::floor(-1.0)).unwrap();
    hold_sideways(&mut problem, -1.0, 1.0);
    let solution = problem.solve().unwrap();
    let weight = m.density * GRAVITY * 32.0;
    let error = (solution.floor_force.z - weight) / weight;
    println!(
        "floor: reaction {:.4} dyn, weight {weight:.4} dyn, error {:.2e}, sag {:.4} cm, {} Newton \
         iterations, relative residual {:.1e}",
        solution.floor_force.z,
        error,
        -solution.max_displacement().1.z,
        solution.report.iterations,
        solution.report.relative_residual
    );
    assert!(solution.report.converged);
    // The floor is a bound, not a penalty: its reaction is the weight to the solver's
    // tolerance, in a few Newton steps.
    assert!(error.abs() < 1e-6, "{error}");
    assert!(
        solution.report.iterations <= 8,
        "{} Newton iterations",
        solution.report.iterations
    );
    assert_eq!(solution.report.max_penetration, 0.0);
    assert!((solution.weight.z + weight).abs() < 1e-9 * weight);
    // The rollers carry no weight and almost no sideways force.
    assert!(solution.clamp_force.z.abs() < 1e-6 * weight);
    assert!(
        solution.clamp_force.length() < 1e-6 * weight,
        "{}",
        solution.clamp_force
    );
    // The bottom stays on the floor, exactly.
    let lowest = solution
        .positions
        .iter()
        .map(|p| p.z)
        .fold(f64::INFINITY, f64::min);
    assert!(lowest >= -1.0 - 1e-12, "{lowest}");
}

#[test]
fn a_bar_lifted_at_one_end_leaves_the_floor_there_and_rests_on_it_elsewhere() {
    // A 4 × 1 × 1 cm bar of soft tissue on a frictionless floor, its end x = 2 clamped 0.5 cm
    // up: the floor lets go of the bottom near the lifted end (it cannot pull) and carries the
    // rest of the weight; floor + clamp + weight balance. A floor that held every vertex it
    // touched would keep the whole bottom on it.
    let mesh = tissue_mesh::tet_box(16, 4, 4, Vec3::new(4.0, 1.0, 1.0)).unwrap();
    let m = tissue();
    let mut problem = StaticProblem::new(&mesh, m).unwrap();
    problem.set_floor(Plane::floor(-0.5)).unwrap();
    for n in problem.nodes_where(|p| p.x > 2.0 - 1e-6) {
        let p = problem.rest_positions()[n as usize];
        problem.clamp_at(n, p + DVec3::Z * 0.5).unwrap();
    }
    let solution = problem.solve().unwrap();
    let r = solution.report;
    assert!(r.converged, "{r:?}");
    assert!(r.iterations <= 30, "{r:?}");
    let weight = m.density * GRAVITY * 4.0;
    let balance = solution.floor_force + solution.clamp_force + solution.weight;
    assert!(balance.length() < 1e-6 * weight, "{balance}");
    // The floor pushes, and carries part of the weight; the clamp the rest.
    assert!(
        solution.floor_force.z > 0.05 * weight && solution.floor_force.z < 0.95 * weight,
        "floor {} of a weight {weight}",
        solution.floor_force.z
    );
    assert!(solution.floor_force.x.abs() + solution.floor_force.y.abs() < 1e-9 * weight);
    let bottom = problem.nodes_where(|p| p.z < -0.5 + 1e-6);
    let gap = |n: u32| solution.positions[n as usize].z + 0.5;
    let on = bottom.iter().filter(|&&n| gap(n) < 1e-9).count();
    let off = bottom.iter().filter(|&&n| gap(n) > 1e-3).count();
    println!(
        "lifted bar: floor {:.1} dyn of {weight:.1} dyn, {on} bottom nodes on the floor, {off} \
         off, {} Newton iterations",
        solution.floor_force.z, r.iterations
    );
    assert!(on > 0 && off > 0, "{on} on, {off} off the floor");
    // The far end stays down, the lifted end's bottom is up; nothing below the floor.
    let lowest_at = |x: f64| {
        bottom
            .iter()
            .filter(|&&n| (solution.rest[n as usize].x - x).abs() < 1e-6)
            .map(|&n| gap(n))
            .fold(f64::INFINITY, f64::min)
    };
    assert!(lowest_at(-2.0) < 1e-9, "{}", lowest_at(-2.0));
    assert!(lowest_at(1.75) > 0.1, "{}", lowest_at(1.75));
    assert!(bottom.iter().all(|&n| gap(n) >= -1e-12));
}

#[test]
fn a_column_on_the_floor_shortens_by_rho_g_h2_over_2e() {
    // At ν = 0 a column standing on a frictionless floor is exactly in uniaxial stress
    // σ_zz = −ρ g (top − z) (at ν > 0 the free column would bulge its ends, which the floor
    // flattens), so its top sinks by ρ g H² / (2E) relative to its bottom. 2 × 2 × 2 cm,
    // 4 × 4 × 8 cells; E = 100 kPa keeps the strain at 0.2 % (linear regime).
    let mesh = tissue_mesh::tet_box(4, 4, 8, Vec3::new(2.0, 2.0, 2.0)).unwrap();
    let m = ElasticMaterial {
        young_kpa: 100.0,
        poisson: 0.0,
        density: 1.05,
    };
    let mut problem = StaticProblem::new(&mesh, m).unwrap();
    problem.set_floor(Plane::floor(-1.0)).unwrap();
    hold_sideways(&mut problem, -1.0, 0.5);
    let solution = problem.solve().unwrap();
    assert!(solution.report.converged);
    let top = problem.nodes_where(|p| p.z > 1.0 - 1e-6);
    let bottom = problem.nodes_where(|p| p.z < -1.0 + 1e-6);
    let sink = solution.mean_displacement(&bottom).z - solution.mean_displacement(&top).z;
    let column = m.density * GRAVITY * 4.0 / (2.0 * m.young());
    println!(
        "column: top sinks {sink:.6} cm, theory {column:.6} cm ({:+.3} %)",
        100.0 * (sink - column) / column
    );
    assert!(((sink - column) / column).abs() < 0.01);
}

#[test]
fn a_frictionless_plate_squeezes_a_block_into_uniaxial_stress() {
    // 2 × 2 × 1 cm between a floor at z = −0.5 and a plate on top moved down 0.2 % of the
    // height: frictionless on both faces, so the stress is uniaxial, F = E A ε.
    let mesh = tissue_mesh::tet_box(4, 4, 2, Vec3::new(2.0, 2.0, 1.0)).unwrap();
    let m = tissue();
    let mut problem = StaticProblem::new(&mesh, m).unwrap();
    problem.set_gravity(DVec3::ZERO).unwrap();
    problem.set_floor(Plane::floor(-0.5)).unwrap();
    let strain = 0.002;
    problem
        .set_plate(Plate {
            rest: Plane {
                point: DVec3::new(0.0, 0.0, 0.5),
                normal: -DVec3::Z,
            },
            displacement: strain * 1.0,
        })
        .unwrap();
    hold_sideways(&mut problem, -0.5, 0.5);
    let solution = problem.solve().unwrap();
    assert!(solution.report.converged);
    let expected = m.young() * 4.0 * strain;
    let plate = -solution.plate_force.z;
    println!(
        "plate: {plate:.3} dyn against E A ε = {expected:.3} dyn ({:+.2} %), floor {:.3} dyn",
        100.0 * (plate - expected) / expected,
        solution.floor_force.z
    );
    assert!(((plate - expected) / expected).abs() < 0.01);
    assert!((solution.floor_force.z - plate).abs() < 1e-6 * plate);
}

#[test]
fn a_bar_stretched_by_its_clamps_pulls_back_with_e_a_epsilon() {
    // ν = 0: clamping the ends whole does not disturb the uniform stretch.
    let m = ElasticMaterial {
        poisson: 0.0,
        ..tissue()
    };
    let mesh = tissue_mesh::tet_box(8, 2, 2, Vec3::new(4.0, 1.0, 1.0)).unwrap();
    let mut problem = StaticProblem::new(&mesh, m).unwrap();
    problem.set_gravity(DVec3::ZERO).unwrap();
    let strain = 0.001;
    problem.clamp_where(|p| p.x < -2.0 + 1e-6);
    for n in problem.nodes_where(|p| p.x > 2.0 - 1e-6) {
        let p = problem.rest_positions()[n as usize];
        problem.clamp_at(n, p + DVec3::X * (4.0 * strain)).unwrap();
    }
    let solution = problem.solve().unwrap();
    assert!(solution.report.converged);
    let expected = m.young() * 1.0 * strain;
    let pulled: f64 = (0..solution.positions.len() as u32)
        .filter(|&n| solution.rest[n as usize].x > 2.0 - 1e-6)
        .map(|n| solution.reactions[n as usize].x)
        .sum();
    println!("bar: reaction {pulled:.4} dyn against E A ε = {expected:.4} dyn");
    assert!(
        ((pulled - expected) / expected).abs() < 0.005,
        "{pulled} vs {expected}"
    );
    assert!(solution.clamp_force.length() < 1e-6 * expected);
}
