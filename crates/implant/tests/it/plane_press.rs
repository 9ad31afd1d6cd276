//! The plane press of SPEC Table 1: the thesis's 65² run against its area, the invariants every
//! run must keep, the region's orientation, cancel and the parameter errors.
//!
//! The runs here go at 400 cm/s, four times the default speed, to stay short: the area after
//! does not depend on the speed (at 65², 0.6675–0.6718 cm² for every speed from 50 to 400 cm/s;
//! see [`PlanePressParams::default`]), and the invariants hold at any speed.

use std::ops::ControlFlow;

use glam::{Quat, Vec3};
use tissue_implant::{
    plane_press, plane_press_region, ImplantError, PlanePressOutcome, PlanePressParams, Progress,
};
use tissue_mesh::TriMesh;

/// The speed of the runs here (cm/s; module docs).
const FAST: f32 = 400.0;

fn fast() -> PlanePressParams {
    PlanePressParams {
        speed: FAST,
        ..PlanePressParams::default()
    }
}

fn top(mesh: &TriMesh, up: Vec3) -> f32 {
    mesh.positions()
        .iter()
        .map(|p| p.dot(up))
        .fold(f32::MIN, f32::max)
}

/// The checks every run must pass; `up` is the region's normal.
fn check_invariants(out: &PlanePressOutcome, params: &PlanePressParams, up: Vec3) {
    assert!(out.is_finite());
    assert!(out.boundary_unchanged);
    assert!(
        out.area_after > out.area_before,
        "{} → {}",
        out.area_before,
        out.area_after
    );
    assert!(out.volume_difference > 0.0, "{}", out.volume_difference);
    // No layer-2 edge through the sphere beyond 1 % of its radius.
    assert!(
        out.max_penetration <= 0.01 * params.sphere_radius,
        "penetration {}",
        out.max_penetration
    );
    // The sphere got there: its centre at the region's centroid (to the step's rounding) …
    assert!(
        out.sphere_centre.distance(out.target) < 1e-4,
        "centre {} target {}",
        out.sphere_centre,
        out.target
    );
    // … under both layers: layer 2 over the sphere's top, the skin over layer 2.
    let sphere = top(&out.sphere_after, up);
    let inner = top(&out.inner_after, up);
    let skin = top(&out.region_after, up);
    assert!(inner > sphere && skin > inner, "{skin} {inner} {sphere}");
    assert!((sphere - (out.target.dot(up) + params.sphere_radius)).abs() < 1e-3);
    // Constant speed: a whole number of steps covers the travel.
    let covered = f64::from(out.speed) * out.steps as f64 * f64::from(out.time_step);
    assert!((covered - f64::from(out.travel)).abs() < 1e-6 * f64::from(out.travel));
    assert!(out.speed <= params.speed && out.speed > 0.99 * params.speed);
}

#[test]
fn the_65_plane_press_stretches_the_region_as_the_thesis_did() {
    let region = plane_press_region(65).unwrap();
    // The thesis's region: 3922 vertices and 7504 triangles over both layers, 0.458 cm².
    assert_eq!(region.mesh().vertex_count(), 1945);
    assert_eq!(region.mesh().triangle_count(), 3736);
    let params = fast();
    let mut calls = 0u64;
    let out = plane_press(region.mesh(), &params, |p| {
        calls += 1;
        assert_eq!(p.steps, calls);
        assert!(p.steps <= p.max_steps);
        assert_eq!(p.last.remaining_crossings, 0);
        ControlFlow::Continue(())
    })
    .unwrap();
    assert_eq!(calls, out.steps);
    check_invariants(&out, &params, Vec3::Z);
    assert!(
        (out.area_before - 0.456).abs() < 1e-3,
        "{}",
        out.area_before
    );
    // The thesis: 0.458 → 0.672 cm², 0.062 cm³ (measured here: 0.671 cm², 0.061 cm³).
    assert!(
        (out.area_after - 0.672).abs() < 0.15 * 0.672,
        "area after {}",
        out.area_after
    );
    assert!(
        (out.volume_difference - 0.062).abs() < 0.15 * 0.062,
        "volume {}",
        out.volume_difference
    );
}

#[test]
fn a_tilted_region_gives_the_same_press() {
    let flat = plane_press_region(33).unwrap();
    let params = fast();
    let out = plane_press(flat.mesh(), &params, |_| ControlFlow::Continue(())).unwrap();
    check_invariants(&out, &params, Vec3::Z);

    // The same region turned and moved: the sphere comes along its mean normal.
    let turn = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 1.1);
    let shift = Vec3::new(0.3, -0.2, 1.5);
    let tilted = flat
        .mesh()
        .with_positions(
            flat.mesh()
                .positions()
                .iter()
                .map(|&p| turn * p + shift)
                .collect(),
        )
        .unwrap();
    let turned = plane_press(&tilted, &params, |_| ControlFlow::Continue(())).unwrap();
    let up = turn * Vec3::Z;
    assert!(turned.is_finite() && turned.boundary_unchanged);
    assert!(turned.max_penetration <= 0.01 * params.sphere_radius);
    assert!(turned.sphere_centre.distance(turned.target) < 3e-4);
    assert!(top(&turned.region_after, up) > top(&turned.sphere_after, up));
    assert_eq!(turned.steps, out.steps);
    let relative = |a: f64, b: f64| (a - b).abs() / b;
    assert!(relative(turned.area_before, out.area_before) < 1e-5);
    assert!(
        relative(turned.area_after, out.area_after) < 0.005,
        "{} vs {}",
        turned.area_after,
        out.area_after
    );
    assert!(
        relative(turned.volume_difference, out.volume_difference) < 0.01,
        "{} vs {}",
        turned.volume_difference,
        out.volume_difference
    );
}

#[test]
fn cancel_stops_the_run() {
    let region = plane_press_region(33).unwrap();
    let result = plane_press(region.mesh(), &PlanePressParams::default(), |p| {
        if p.steps == 5 {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    });
    assert!(matches!(result, Err(ImplantError::Cancelled { steps: 5 })));
}

#[test]
fn bad_parameters_are_refused() {
    let region = plane_press_region(33).unwrap();
    let never = |_: &Progress| -> ControlFlow<()> { panic!("no step expected") };
    for (name, params) in [
        (
            "speed",
            PlanePressParams {
                speed: 0.0,
                ..PlanePressParams::default()
            },
        ),
        (
            "depth",
            PlanePressParams {
                depth: -0.05,
                ..PlanePressParams::default()
            },
        ),
        (
            "sphere_radius",
            PlanePressParams {
                sphere_radius: f32::NAN,
                ..PlanePressParams::default()
            },
        ),
        // So slow that the travel would take more than the step limit.
        (
            "speed",
            PlanePressParams {
                speed: 1e-3,
                ..PlanePressParams::default()
            },
        ),
    ] {
        match plane_press(region.mesh(), &params, never) {
            Err(ImplantError::InvalidParameter { param: got, .. }) => assert_eq!(got.name(), name),
            other => panic!("{name}: expected InvalidParameter, got {other:?}"),
        }
    }
}
