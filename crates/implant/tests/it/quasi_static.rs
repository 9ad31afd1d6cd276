//! The quasi-static solver against the explicit run it replaces, on Table 2.
#![allow(clippy::unwrap_used)]

use std::ops::ControlFlow;

use glam::Vec3;
use tissue_implant::{
    default_radius, place_implant, select_region_with, ImplantShape, ImplantSpec, Insertion,
    InsertionOutcome, InsertionParams, RegionOptions, RegionRule, RegionSelection, Solver,
    TissueLayers,
};

fn region() -> RegionSelection {
    let patient = tissue_mesh::grid(65, 20.0).unwrap();
    select_region_with(
        &patient,
        Vec3::ZERO,
        default_radius(3.5).unwrap(),
        &RegionOptions {
            rule: RegionRule::TouchesVertex,
            ..RegionOptions::default()
        },
    )
    .unwrap()
}

fn run(selection: &RegionSelection, volume: f64, params: &InsertionParams) -> InsertionOutcome {
    let layers = TissueLayers::new(selection.mesh(), &params.layers).unwrap();
    let spec = ImplantSpec::new(ImplantShape::Round { diameter: 7.0 }, volume);
    let implant = place_implant(&layers, &spec, Vec3::ZERO, Vec3::Z, Vec3::X).unwrap();
    let mut insertion = Insertion::new(selection.mesh(), &implant, params).unwrap();
    insertion.run(|_| ControlFlow::Continue(())).unwrap()
}

fn describe(o: &InsertionOutcome) -> String {
    format!(
        "{:?}: gain {:.3} cm², volume difference {:.3} cm³, compression {:.3} %, penetration {:.4}, {} iterations, residual {:?} N, {:?}, {:.3} s",
        o.solver,
        o.area_gain,
        o.volume_difference,
        100.0 * o.implant_compression,
        o.max_penetration,
        o.iterations,
        o.residual_n,
        o.stop_reason,
        o.wall_time.as_secs_f64()
    )
}

#[test]
fn table_2_quasi_static_agrees_with_explicit() {
    let selection = region();
    for volume in [50.0, 100.0, 150.0] {
        let explicit = run(
            &selection,
            volume,
            &InsertionParams {
                solver: Solver::Explicit,
                ..InsertionParams::default()
            },
        );
        let statics = run(&selection, volume, &InsertionParams::default());
        eprintln!("{volume}: {}\n{volume}: {}", describe(&explicit), describe(&statics));
    }
}
