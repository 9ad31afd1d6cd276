//! The quasi-static solver against the explicit run it replaces, on Table 2.
#![allow(clippy::unwrap_used)]

use std::ops::ControlFlow;

use glam::Vec3;
use tissue_implant::{
    place_implant, ImplantShape, ImplantSpec, Insertion, InsertionOutcome, InsertionParams,
    RegionSelection, Solver, TissueLayers,
};

use crate::table2::region;

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

/// Table 2 at 50 cm³ (where the solver converges; module `quasi_static`'s status): the
/// quasi-static solve settles on its tolerance, and its gain, volume difference and implant
/// volume agree with the explicit run's within 2 %, with nothing through the expander and the
/// boundary unchanged; tightening the tolerance tenfold moves the gain by less than 0.1 %.
#[test]
fn table_2_at_50_cm3_quasi_static_agrees_with_explicit() {
    let selection = region();
    let explicit = run(
        &selection,
        50.0,
        &InsertionParams {
            solver: Solver::Explicit,
            ..InsertionParams::default()
        },
    );
    let params = InsertionParams {
        solver: Solver::QuasiStatic,
        ..InsertionParams::default()
    };
    let statics = run(&selection, 50.0, &params);
    eprintln!("{}\n{}", describe(&explicit), describe(&statics));
    assert_eq!(statics.solver, Solver::QuasiStatic);
    assert_eq!(statics.stop_reason, tissue_mss::StopReason::Settled);
    assert!(statics.residual_n.is_some_and(|r| r.is_finite() && r > 0.0));
    assert!(statics.iterations > 0 && statics.iterations < params.statics.max_iterations);
    assert!(statics.boundary_unchanged && statics.is_finite());
    assert_eq!(statics.max_penetration, 0.0);
    let close = |a: f64, b: f64, what: &str| {
        assert!(
            (a - b).abs() <= 0.02 * b.abs(),
            "{what}: {a} against explicit {b}"
        );
    };
    close(statics.area_gain, explicit.area_gain, "gain");
    close(
        statics.volume_difference,
        explicit.volume_difference,
        "volume difference",
    );
    assert!(statics.implant_compression.abs() <= 0.01);

    let tighter = InsertionParams {
        statics: tissue_implant::StaticParams {
            tolerance: params.statics.tolerance / 10.0,
            ..params.statics.clone()
        },
        ..params.clone()
    };
    let refined = run(&selection, 50.0, &tighter);
    eprintln!("{}", describe(&refined));
    assert_eq!(refined.stop_reason, tissue_mss::StopReason::Settled);
    assert!(
        (refined.area_gain - statics.area_gain).abs() <= 1e-3 * statics.area_gain,
        "tolerance / 10: gain {} against {}",
        refined.area_gain,
        statics.area_gain
    );
}

/// A parameter acts physically through the quasi-static solve as through the explicit run:
/// twice the skin's Young's modulus squeezes the 50 cm³ expander more (its pressure holds a
/// stiffer skin) and stretches the skin less, by the explicit run's ratios (compression × 1.34,
/// gain − 3.5 %) within a tenth of the change.
#[test]
fn twice_the_skin_stiffness_acts_as_in_the_explicit_run() {
    let selection = region();
    let outcome = |solver: Solver, factor: f64| {
        let mut params = InsertionParams {
            solver,
            ..InsertionParams::default()
        };
        params.layers.young *= factor;
        run(&selection, 50.0, &params)
    };
    let change = |solver: Solver| {
        let (soft, stiff) = (outcome(solver, 1.0), outcome(solver, 2.0));
        assert_eq!(stiff.stop_reason, tissue_mss::StopReason::Settled);
        (
            stiff.implant_compression / soft.implant_compression,
            stiff.area_gain / soft.area_gain,
        )
    };
    let (explicit_squeeze, explicit_gain) = change(Solver::Explicit);
    let (static_squeeze, static_gain) = change(Solver::QuasiStatic);
    eprintln!(
        "E × 2: compression × {static_squeeze:.3} (explicit × {explicit_squeeze:.3}), gain × \
         {static_gain:.4} (explicit × {explicit_gain:.4})"
    );
    assert!(static_squeeze > 1.2 && static_gain < 0.99);
    assert!((static_squeeze - explicit_squeeze).abs() <= 0.1 * (explicit_squeeze - 1.0));
    assert!((static_gain - explicit_gain).abs() <= 0.1 * (1.0 - explicit_gain));
}

/// Table 2 at 100 cm³, where the contacts carry the expander's pressure (55 kPa): the solve
/// settles with nothing through the expander (layer 2's edges are held off the dome's bulge,
/// not only its particles: 0.037 cm crossed before) and agrees with the explicit run within
/// 2 % (gain, volume difference), the implant's volume within 1 %.
#[test]
fn table_2_at_100_cm3_quasi_static_holds_the_skin_off_the_expander() {
    let selection = region();
    let explicit = run(&selection, 100.0, &InsertionParams::default());
    let params = InsertionParams {
        solver: Solver::QuasiStatic,
        ..InsertionParams::default()
    };
    let statics = run(&selection, 100.0, &params);
    eprintln!("{}\n{}", describe(&explicit), describe(&statics));
    assert_eq!(statics.stop_reason, tissue_mss::StopReason::Settled);
    assert!(statics.boundary_unchanged && statics.is_finite());
    assert_eq!(statics.max_penetration, 0.0);
    for (what, a, b) in [
        ("gain", statics.area_gain, explicit.area_gain),
        (
            "volume difference",
            statics.volume_difference,
            explicit.volume_difference,
        ),
    ] {
        assert!((a - b).abs() <= 0.02 * b.abs(), "{what}: {a} against {b}");
    }
    assert!(statics.implant_compression.abs() <= 0.01);
}
