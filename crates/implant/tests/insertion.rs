//! The insertion run on a coarse flat patient: the checks every run must pass (SPEC A.5 and the
//! issue's validation list), cancel, and the error for an implant larger than its region.

use std::ops::ControlFlow;

use glam::Vec3;
use tissue_implant::{
    place_implant, select_region_with, ImplantError, ImplantShape, ImplantSpec, Insertion,
    InsertionOutcome, InsertionParams, Layer, RegionOptions, RegionRule, RegionSelection,
    TissueLayers,
};
use tissue_mesh::TriMesh;
use tissue_mss::StopReason;

/// A 20 cm plane of 33² vertices, the region of radius 5.25 cm at its centre, a round 7 cm
/// implant of `volume` with about 200 vertices.
fn scene(volume: f64) -> (TriMesh, RegionSelection, Insertion, InsertionParams) {
    let patient = tissue_mesh::grid(33, 20.0).unwrap();
    let selection = select_region_with(
        &patient,
        Vec3::ZERO,
        5.25,
        &RegionOptions {
            rule: RegionRule::TouchesVertex,
            ..RegionOptions::default()
        },
    )
    .unwrap();
    let params = InsertionParams::default();
    let layers = TissueLayers::new(selection.mesh(), &params.layers).unwrap();
    let spec =
        ImplantSpec::new(ImplantShape::Round { diameter: 7.0 }, volume).with_vertex_budget(200);
    let implant = place_implant(&layers, &spec, Vec3::ZERO, Vec3::Z, Vec3::X).unwrap();
    let insertion = Insertion::new(selection.mesh(), &implant, &params).unwrap();
    (patient, selection, insertion, params)
}

fn run(volume: f64) -> (TriMesh, RegionSelection, InsertionOutcome, InsertionParams) {
    let (patient, selection, mut insertion, params) = scene(volume);
    let mut calls = 0u64;
    let outcome = insertion
        .run(|p| {
            calls += 1;
            assert_eq!(p.steps, calls);
            ControlFlow::Continue(())
        })
        .unwrap();
    assert_eq!(calls, outcome.steps);
    (patient, selection, outcome, params)
}

#[test]
fn a_run_settles_over_the_implant_and_keeps_every_invariant() {
    let volume = 50.0;
    let (patient, selection, out, params) = run(volume);
    assert_eq!(out.stop_reason, StopReason::Settled, "{} steps", out.steps);
    assert!(out.is_finite());
    assert!(out.boundary_unchanged);
    // No layer-2 edge through the implant: penetration at most 1 % of its height.
    assert!(
        f64::from(out.max_penetration) <= 0.01 * out.dome_height,
        "penetration {} cm",
        out.max_penetration
    );
    // The skin went up over the implant: it gained area and encloses at least the implant's
    // volume (the slab above it adds more), and the layers did not turn inside out.
    assert!(
        out.area_gain > 0.02 * out.area_before,
        "gain {}",
        out.area_gain
    );
    assert!(
        out.volume_difference > 0.95 * volume && out.volume_difference < 2.0 * volume,
        "volume difference {}",
        out.volume_difference
    );
    let centre = selection.patient_to_region()[patient
        .positions()
        .iter()
        .position(|p| p.length() < 1e-5)
        .unwrap()] as usize;
    let thickness = out.region_after.positions()[centre].z - out.inner_after.positions()[centre].z;
    assert!(
        f64::from(thickness) > 0.5 * params.layers.depth,
        "slab at the centre {thickness} cm thick"
    );
    // The top of the skin is above the top of the implant.
    let apex = out
        .implant_after
        .positions()
        .iter()
        .map(|p| p.z)
        .fold(f32::MIN, f32::max);
    assert!(out.region_after.positions()[centre].z > apex);
    // The implant is squeezed, not emptied.
    assert!(
        out.implant_compression.abs() < 0.2,
        "{}",
        out.implant_compression
    );
    // Per-vertex fields for pictures, and the patient with the region put back, seam closed.
    assert_eq!(out.displacement.len(), selection.mesh().vertex_count());
    assert!(out.stretch.iter().all(|s| s.is_finite() && *s > 0.0));
    let after = out.patient_after(&patient, &selection).unwrap();
    for loop_ in selection.boundary_loops() {
        for &r in loop_ {
            let p = selection.region_to_patient()[r as usize] as usize;
            assert_eq!(
                after.positions()[p].to_array().map(f32::to_bits),
                patient.positions()[p].to_array().map(f32::to_bits)
            );
        }
    }
}

#[test]
fn a_larger_implant_gains_more_area() {
    let (_, _, small, _) = run(30.0);
    let (_, _, large, _) = run(60.0);
    assert!(
        large.area_gain > small.area_gain * 1.3,
        "{} vs {}",
        large.area_gain,
        small.area_gain
    );
    assert!(large.volume_difference > small.volume_difference);
}

#[test]
fn the_caller_cancels_between_steps() {
    let (_, _, mut insertion, _) = scene(50.0);
    let err = insertion
        .run(|p| {
            if p.steps == 25 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        })
        .unwrap_err();
    assert_eq!(err, ImplantError::Cancelled { steps: 25 });
    assert_eq!(insertion.contact_run().steps(), 25);
}

#[test]
fn an_implant_wider_than_its_region_is_refused() {
    let patient = tissue_mesh::grid(33, 20.0).unwrap();
    let selection = tissue_implant::select_region(&patient, Vec3::ZERO, 2.0).unwrap();
    let layers = TissueLayers::new(selection.mesh(), &InsertionParams::default().layers).unwrap();
    let spec = ImplantSpec::new(ImplantShape::Round { diameter: 7.0 }, 50.0);
    let err = place_implant(&layers, &spec, Vec3::ZERO, Vec3::Z, Vec3::X).unwrap_err();
    assert!(
        matches!(err, ImplantError::FootprintOutsideRegion { .. }),
        "{err}"
    );
    let _ = Layer::Inner;
}
