//! The thesis's volume check (SPEC A.2): a closed 2 cm cube (386 vertices, 8 cm³) whose top is
//! pressed down keeps its volume with the Vassilev–Spanlang springs and loses it without them.
#![allow(clippy::unwrap_used)]

use glam::Vec3;
use tissue_mesh::subdivided_cube;
use tissue_mss::{
    masses_from_triangles, springs_from_triangles, Integrator, MassSpringSystem, Particles,
    SheetMaterial, StopCriterion, StopReason, VolumePreservation,
};

/// Runs the press until it settles (symplectic Euler, step `h`); returns the final enclosed volume (cm³) and how far the top centre sank (cm).
fn press_with(
    volume_springs: bool,
    strength: f32,
    k_v: f32,
    c: f32,
    h: f32,
    damping: f32,
) -> (f64, f32) {
    let cube = subdivided_cube(8, 2.0).unwrap();
    assert_eq!(cube.vertex_count(), 386);
    let material = SheetMaterial {
        young: 1.0e4,
        poisson: 0.3,
        thickness: 0.1,
    };
    let masses = masses_from_triangles(&cube, cube.area() * 0.1 * 1.0).unwrap();
    let mut particles = Particles::new(cube.positions(), &masses).unwrap();
    let top: Vec<usize> = (0..cube.vertex_count())
        .filter(|&v| cube.positions()[v].z > 0.999)
        .collect();
    for v in 0..cube.vertex_count() {
        if cube.positions()[v].z < -0.999 {
            particles.fix(v as u32).unwrap(); // the cube stands on a table
        }
    }
    let springs = springs_from_triangles(&cube, &material, 0).unwrap();
    let mut system = MassSpringSystem::new(particles, springs).unwrap();
    // A uniform pressure on the top face, `strength` dyn in all.
    let mut field = vec![Vec3::ZERO; cube.vertex_count()];
    for &v in &top {
        field[v] = Vec3::new(0.0, 0.0, -strength / top.len() as f32);
    }
    system.set_external_forces(&field).unwrap();
    if volume_springs {
        system
            .add_volume_preservation(VolumePreservation::new(&cube, &masses, 0, k_v, c).unwrap())
            .unwrap();
    }
    system.set_integrator(Integrator::SymplecticEuler);
    system.set_damping(damping).unwrap();
    let report = system
        .run(
            h,
            &StopCriterion {
                window: 1000,
                floor: FLOOR,
                tolerance: 1e-4,
                max_steps: 300_000,
            },
        )
        .unwrap();
    let after = cube
        .with_positions(
            system
                .particles()
                .positions()
                .iter()
                .map(|&p| Vec3::from(p))
                .collect(),
        )
        .unwrap();
    let centre_top = top
        .iter()
        .map(|&v| after.positions()[v])
        .fold(Vec3::ZERO, |a, p| a + p)
        / top.len() as f32;
    assert_eq!(report.reason, StopReason::Settled, "{report:?}");
    (after.signed_volume().unwrap(), 1.0 - centre_top.z)
}

/// Total push on the top face (dyn), and the volume springs' parameters.
const STRENGTH: f32 = 100.0;
const K_V: f32 = 2.0;
const C: f32 = 0.1;
/// Settled when the summed displacement stays under 1e-4 cm a step (about 3e-7 cm per particle,
/// the f32 noise of this scene) for 1000 steps.
const FLOOR: f64 = 1e-4;

#[test]
fn pressed_cube_keeps_its_volume_with_volume_springs_only() {
    let (with, sank_with) = press_with(true, STRENGTH, K_V, C, 1e-4, 0.99);
    let (without, sank_without) = press_with(false, STRENGTH, K_V, C, 1e-4, 0.99);
    eprintln!(
        "with: {with} cm³, top sank {sank_with} cm; without: {without} cm³, sank {sank_without} cm"
    );
    // The volume is kept by bulging, not by stiffness: the top still sinks far enough that its
    // descent alone (over the 4 cm² face) would remove more than 10% of the volume.
    assert!(
        sank_with * 4.0 > 0.1 * 8.0,
        "with volume springs the top sank only {sank_with} cm"
    );
    assert!(sank_without > sank_with);
    assert!(
        (with - 8.0).abs() < 0.01 * 8.0,
        "with volume springs: {with} cm³, not within 1% of 8"
    );
    // Without them the hollow box has nothing against collapse (springs give no bending
    // stiffness, and there is no self-contact here): its top goes down towards the bottom.
    assert!(
        without < 0.9 * 8.0,
        "without volume springs: {without} cm³ should lose more than 10%"
    );
}
