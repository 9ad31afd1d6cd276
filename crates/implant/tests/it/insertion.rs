//! The insertion run on a coarse flat patient: the checks every run must pass (SPEC A.5 and the
//! issue's validation list), cancel, and the error for an implant larger than its region.
#![allow(clippy::unwrap_used)]

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

/// A fine region (0.09 cm edges) on a tight limb (a cylinder of radius 2.75 cm along `y`, its
/// top at the origin): the tube case whose run blew up at half its default simulation edge.
fn limb_region() -> RegionSelection {
    const R: f32 = 2.75;
    let flat = tissue_mesh::grid(89, 8.0).unwrap();
    let wrapped: Vec<Vec3> = flat
        .positions()
        .iter()
        .map(|p| {
            let a = p.x / R;
            Vec3::new(R * a.sin(), p.y, R * a.cos() - R)
        })
        .collect();
    let limb = flat.with_positions(wrapped).unwrap();
    select_region_with(&limb, Vec3::ZERO, 3.0, &RegionOptions::default()).unwrap()
}

/// Signed distance of `x` from the plane of the nearest (by centroid) triangle of `surface`,
/// positive on its normal's side.
fn signed_distance(surface: &TriMesh, x: Vec3) -> f32 {
    let normals = surface.triangle_normals();
    let (t, _) = (0..surface.triangle_count())
        .map(|t| {
            let [a, b, c] = surface.corners(t);
            (t, ((a + b + c) / 3.0).distance_squared(x))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    (x - surface.corners(t)[0]).dot(normals[t])
}

#[test]
fn an_expander_wrapped_round_a_limb_starts_under_layer_2_and_does_not_blow_up() {
    let selection = limb_region();
    let params = InsertionParams::default();
    let layers = TissueLayers::new(selection.mesh(), &params.layers).unwrap();
    let spec =
        ImplantSpec::new(ImplantShape::Round { diameter: 4.0 }, 10.0).with_vertex_budget(300);
    let implant = place_implant(&layers, &spec, Vec3::ZERO, Vec3::Z, Vec3::Y).unwrap();
    // The emptied expander the fill starts from lies under layer 2 everywhere, beside its
    // wrapped rim too (a flat disc through the lowest base vertex stood out of it there).
    let inner = layers.rest(Layer::Inner);
    let highest = implant
        .flat_positions()
        .iter()
        .map(|&x| signed_distance(inner, x))
        .fold(f32::NEG_INFINITY, f32::max);
    assert!(
        highest < 0.0,
        "the empty expander stands {highest} cm out of layer 2"
    );
    let mut insertion = Insertion::new(selection.mesh(), &implant, &params).unwrap();
    let first = insertion.step().unwrap();
    assert_eq!(first.remaining_crossings, 0);
    assert_eq!(first.thinned, 0);
    // Through the fill and after it the skin stays near the dome: it blew up to a 479 cm²
    // "gain" with the flat start.
    for _ in 0..400 {
        insertion.step().unwrap();
    }
    let out = insertion.outcome(std::time::Duration::ZERO).unwrap();
    assert!(out.is_finite() && out.boundary_unchanged);
    assert!(
        f64::from(out.max_displacement) < out.dome_height + 0.25,
        "the skin moved {} cm over a {} cm dome",
        out.max_displacement,
        out.dome_height
    );
    assert!(
        out.area_gain > 0.0 && out.area_gain < 20.0,
        "{}",
        out.area_gain
    );
}
