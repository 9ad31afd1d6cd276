//! Tests of the planning helpers: the parallel sweep and the inverse volume search.
#![allow(clippy::panic)]

use std::cell::RefCell;

use tissue_implant::{
    sweep, volume_for_gain, ImplantError, InverseOptions, InverseSearch, Param, PlanningRun,
};

/// An analytic gain, its exact inverse, and a bracket and target for it.
struct Case {
    name: &'static str,
    gain: fn(f64) -> f64,
    root: f64,
    target: f64,
    bracket: (f64, f64),
}

fn linear(v: f64) -> f64 {
    0.3 * v
}

fn two_thirds(v: f64) -> f64 {
    2.0 * v.powf(2.0 / 3.0)
}

/// A steep sigmoid: 60 cm² total, half at 200 cm³, over a few cm³.
fn sigmoid(v: f64) -> f64 {
    60.0 / (1.0 + (-(v - 200.0) / 3.0).exp())
}

/// The same, steeper still (secant steps alone crawl on it).
fn very_steep(v: f64) -> f64 {
    60.0 / (1.0 + (-(v - 137.0) / 0.5).exp())
}

/// A gain saturating near the target: flat at both bracket ends (interpolation alone crawls).
fn saturating(v: f64) -> f64 {
    30.0 * (v - 300.0).tanh()
}

/// An exponential gain (strongly convex: regula falsi without safeguards crawls from one side).
fn exponential(v: f64) -> f64 {
    1e-3 * (v / 20.0).exp()
}

/// A decreasing gain.
fn decreasing(v: f64) -> f64 {
    100.0 - 0.2 * v
}

fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "linear",
            gain: linear,
            root: 100.0,
            target: 30.0,
            bracket: (10.0, 400.0),
        },
        Case {
            name: "V^(2/3)",
            gain: two_thirds,
            root: 20f64.powf(1.5),
            target: 40.0,
            bracket: (10.0, 500.0),
        },
        Case {
            name: "sigmoid",
            gain: sigmoid,
            root: 200.0 + 3.0 * (60.0f64 / 45.0 - 1.0).ln().abs(),
            target: 45.0,
            bracket: (50.0, 500.0),
        },
        Case {
            name: "very steep sigmoid",
            gain: very_steep,
            root: 137.0,
            target: 30.0,
            bracket: (20.0, 300.0),
        },
        Case {
            name: "saturating",
            gain: saturating,
            root: 300.0 + (29.0f64 / 30.0).atanh(),
            target: 29.0,
            bracket: (10.0, 400.0),
        },
        Case {
            name: "exponential",
            gain: exponential,
            root: 20.0 * 30_000f64.ln(),
            target: 30.0,
            bracket: (10.0, 400.0),
        },
        Case {
            name: "decreasing",
            gain: decreasing,
            root: 300.0,
            target: 40.0,
            bracket: (50.0, 450.0),
        },
    ]
}

/// Runs the search with a closure that records its calls.
fn search(
    case: &Case,
    options: &InverseOptions,
) -> (Result<InverseSearch, ImplantError>, Vec<PlanningRun>) {
    let calls = RefCell::new(Vec::new());
    let result = volume_for_gain(case.target, case.bracket, options, |volume| {
        let gain = (case.gain)(volume);
        calls.borrow_mut().push(PlanningRun { volume, gain });
        Ok(gain)
    });
    (result, calls.into_inner())
}

/// Checks a converged search: within tolerance, within budget, runs exactly the calls.
fn check_converged(case: &Case, options: &InverseOptions) {
    let (result, calls) = search(case, options);
    let found = match result {
        Ok(found) => found,
        Err(e) => panic!("{}: {e}", case.name),
    };
    assert!(found.converged, "{}: not converged: {found:?}", case.name);
    assert_eq!(found.runs, calls, "{}: runs are not the calls", case.name);
    assert!(
        found.runs.len() <= options.max_runs,
        "{}: {} runs for a budget of {}",
        case.name,
        found.runs.len(),
        options.max_runs
    );
    assert!(
        found
            .runs
            .iter()
            .any(|r| r.volume == found.volume && r.gain == found.gain),
        "{}: the answer is not one of the runs",
        case.name
    );
    assert_eq!(found.gain, (case.gain)(found.volume), "{}", case.name);
    // For a monotone gain the answer is the run closest to the target.
    let best = found
        .runs
        .iter()
        .map(|r| (r.gain - case.target).abs())
        .fold(f64::INFINITY, f64::min);
    assert_eq!((found.gain - case.target).abs(), best, "{}", case.name);
    let gain_ok = (found.gain - case.target).abs() <= options.gain_tolerance;
    let volume_ok = (found.volume - case.root).abs() <= options.volume_tolerance;
    assert!(
        gain_ok || volume_ok,
        "{}: V = {} (root {}), gain {} (target {}) after {} runs",
        case.name,
        found.volume,
        case.root,
        found.gain,
        case.target,
        found.runs.len()
    );
    // Every run stays inside the bracket, and the two ends come first.
    assert_eq!(found.runs[0].volume, case.bracket.0, "{}", case.name);
    assert_eq!(found.runs[1].volume, case.bracket.1, "{}", case.name);
    for r in &found.runs {
        assert!(
            (case.bracket.0..=case.bracket.1).contains(&r.volume),
            "{}: run outside the bracket: {r:?}",
            case.name
        );
    }
}

#[test]
fn analytic_roots_with_default_options() {
    let options = InverseOptions::default();
    assert_eq!(options.gain_tolerance, 0.5);
    assert_eq!(options.volume_tolerance, 0.5);
    assert_eq!(options.max_runs, 12);
    for case in cases().iter().filter(|c| c.name != "saturating") {
        check_converged(case, &options);
    }
    // Bisection alone would need 2 + 10 runs from its 390 cm³ bracket; this one is harder.
    let saturating = InverseOptions {
        max_runs: 16,
        ..options
    };
    for case in cases().iter().filter(|c| c.name == "saturating") {
        check_converged(case, &saturating);
    }
}

#[test]
fn analytic_roots_to_tight_tolerances() {
    let options = InverseOptions {
        gain_tolerance: 1e-9,
        volume_tolerance: 1e-9,
        max_runs: 100,
    };
    for case in &cases() {
        check_converged(case, &options);
    }
}

/// Runs taken at the given tolerances (a large budget).
fn runs_taken(case: &Case, tolerance: f64) -> usize {
    let options = InverseOptions {
        gain_tolerance: tolerance,
        volume_tolerance: tolerance,
        max_runs: 1000,
    };
    match search(case, &options).0 {
        Ok(found) if found.converged => found.runs.len(),
        other => panic!("{}: {other:?}", case.name),
    }
}

#[test]
fn run_counts_are_small() {
    // Regression bounds at the default tolerances. Bisection alone needs 2 + 10 runs from these
    // ~400 cm³ brackets; a secant step is exact on a straight line.
    let bounds = [
        ("linear", 3),
        ("V^(2/3)", 6),
        ("sigmoid", 11),
        ("very steep sigmoid", 11),
        ("saturating", 15),
        ("exponential", 7),
        ("decreasing", 3),
    ];
    let all = cases();
    assert_eq!(all.len(), bounds.len());
    for (case, (name, bound)) in all.iter().zip(bounds) {
        assert_eq!(case.name, name);
        let runs = runs_taken(case, 0.5);
        assert!(
            runs <= bound,
            "{name}: {runs} runs, expected at most {bound}"
        );
    }
    // Tight tolerances: superlinear convergence, well under bisection's ~40 runs.
    for case in &all {
        let runs = runs_taken(case, 1e-10);
        assert!(runs <= 20, "{} took {runs} runs", case.name);
    }
}

/// Checks that the search stopped on the bracket width: a run on each side of `root`, at most
/// `volume_tolerance` apart, the answer the one closer to the target.
fn check_closed_bracket(found: &InverseSearch, root: f64, target: f64, volume_tolerance: f64) {
    assert!(found.converged, "{found:?}");
    let below = found
        .runs
        .iter()
        .filter(|r| r.volume <= root)
        .max_by(|a, b| a.volume.total_cmp(&b.volume));
    let above = found
        .runs
        .iter()
        .filter(|r| r.volume >= root)
        .min_by(|a, b| a.volume.total_cmp(&b.volume));
    let (Some(below), Some(above)) = (below, above) else {
        panic!("no run on one side of {root}: {found:?}");
    };
    assert!(
        above.volume - below.volume <= volume_tolerance,
        "final bracket {below:?}..{above:?} wider than {volume_tolerance}"
    );
    let closer = if (below.gain - target).abs() < (above.gain - target).abs() {
        below
    } else {
        above
    };
    assert_eq!((found.volume, found.gain), (closer.volume, closer.gain));
}

#[test]
fn bracket_width_stops_the_search() {
    // A gain tolerance too tight to meet: only the bracket width can stop the search.
    for case in cases()
        .iter()
        .filter(|c| c.name != "linear" && c.name != "decreasing")
    {
        let options = InverseOptions {
            gain_tolerance: 1e-300,
            volume_tolerance: 0.5,
            max_runs: 30,
        };
        let (result, calls) = search(case, &options);
        let found = result.unwrap_or_else(|e| panic!("{}: {e}", case.name));
        assert_eq!(found.runs, calls);
        check_closed_bracket(&found, case.root, case.target, options.volume_tolerance);
        assert!(
            found.runs.len() <= 16,
            "{}: {} runs",
            case.name,
            found.runs.len()
        );
    }
}

#[test]
fn a_discontinuous_gain_is_bracketed() {
    // A jump from 0 to 60 cm² at 137.3 cm³: no volume gives 30 cm², the bracket closes on the
    // jump, in about as many runs as bisection (2 + 10 from 390 cm³ to 0.5 cm³).
    let options = InverseOptions::default();
    let jump = |v: f64| if v < 137.3 { 0.0 } else { 60.0 };
    let calls = RefCell::new(0usize);
    let found = volume_for_gain(30.0, (10.0, 400.0), &options, |v| {
        *calls.borrow_mut() += 1;
        Ok(jump(v))
    })
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(found.runs.len(), *calls.borrow());
    check_closed_bracket(&found, 137.3, 30.0, options.volume_tolerance);
    assert!(found.runs.len() <= 12, "{} runs", found.runs.len());
}

#[test]
fn ends_within_tolerance_are_answers() {
    // Either end may be the answer, even when the target lies just outside the bracket.
    for (target, answer) in [
        (3.2, (10.0, 3.0)),
        (2.8, (10.0, 3.0)),
        (119.8, (400.0, 120.0)),
    ] {
        let calls = RefCell::new(0usize);
        let found = volume_for_gain(target, (10.0, 400.0), &InverseOptions::default(), |v| {
            *calls.borrow_mut() += 1;
            Ok(linear(v))
        });
        let found = found.unwrap_or_else(|e| panic!("{e}"));
        assert!(found.converged);
        assert_eq!((found.volume, found.gain), answer, "target {target}");
        assert_eq!(found.runs.len(), 2);
        assert_eq!(*calls.borrow(), 2);
    }
}

#[test]
fn budget_exhausted_is_not_converged() {
    let case = &cases()[3];
    assert_eq!(case.name, "very steep sigmoid");
    let options = InverseOptions {
        max_runs: 4,
        ..InverseOptions::default()
    };
    let (result, calls) = search(case, &options);
    let found = result.unwrap_or_else(|e| panic!("{e}"));
    assert!(!found.converged);
    assert_eq!(found.runs.len(), 4);
    assert_eq!(found.runs, calls);
    // The answer is the better end of the final bracket: a run, and the closest one to the target.
    let best = found
        .runs
        .iter()
        .map(|r| (r.gain - case.target).abs())
        .fold(f64::INFINITY, f64::min);
    assert_eq!((found.gain - case.target).abs(), best);
}

#[test]
fn target_outside_the_bracket_is_refused() {
    for (target, name) in [(200.0, "above"), (1.0, "below")] {
        let calls = RefCell::new(0usize);
        let result = volume_for_gain(target, (10.0, 400.0), &InverseOptions::default(), |v| {
            *calls.borrow_mut() += 1;
            Ok(linear(v))
        });
        assert_eq!(
            result,
            Err(ImplantError::TargetNotBracketed {
                target,
                low_volume: 10.0,
                low_gain: 3.0,
                high_volume: 400.0,
                high_gain: 120.0,
            }),
            "{name}"
        );
        assert_eq!(*calls.borrow(), 2, "{name}");
    }
    // A gain that is not monotone over the bracket: both ends below the target.
    let hump = |v: f64| Ok(50.0 - (v - 100.0).powi(2) / 100.0);
    let result = volume_for_gain(40.0, (0.5, 199.5), &InverseOptions::default(), hump);
    assert!(matches!(
        result,
        Err(ImplantError::TargetNotBracketed { low_volume, high_volume, .. })
            if low_volume == 0.5 && high_volume == 199.5
    ));
}

#[test]
fn run_errors_propagate_unchanged() {
    for fail_at in [1usize, 2, 3, 5] {
        let calls = RefCell::new(0usize);
        let result = volume_for_gain(45.0, (50.0, 500.0), &InverseOptions::default(), |v| {
            let mut n = calls.borrow_mut();
            *n += 1;
            if *n == fail_at {
                Err(ImplantError::Cancelled { steps: 7 })
            } else {
                Ok(sigmoid(v))
            }
        });
        assert_eq!(
            result,
            Err(ImplantError::Cancelled { steps: 7 }),
            "failing at call {fail_at}"
        );
        assert_eq!(*calls.borrow(), fail_at, "the search stops at the error");
    }
}

#[test]
fn non_finite_gains_are_refused() {
    for bad in [f64::NAN, f64::INFINITY] {
        let result = volume_for_gain(30.0, (10.0, 400.0), &InverseOptions::default(), |v| {
            Ok(if v > 50.0 && v < 400.0 {
                bad
            } else {
                linear(v)
            })
        });
        assert!(
            matches!(
                result,
                Err(ImplantError::InvalidParameter {
                    param: Param::Gain,
                    ..
                })
            ),
            "{result:?}"
        );
    }
}

#[test]
fn invalid_options_and_brackets_are_refused() {
    let default = InverseOptions::default();
    let bad_options = [
        (
            "gain_tolerance",
            InverseOptions {
                gain_tolerance: 0.0,
                ..default.clone()
            },
        ),
        (
            "gain_tolerance",
            InverseOptions {
                gain_tolerance: -0.5,
                ..default.clone()
            },
        ),
        (
            "gain_tolerance",
            InverseOptions {
                gain_tolerance: f64::NAN,
                ..default.clone()
            },
        ),
        (
            "gain_tolerance",
            InverseOptions {
                gain_tolerance: f64::INFINITY,
                ..default.clone()
            },
        ),
        (
            "volume_tolerance",
            InverseOptions {
                volume_tolerance: 0.0,
                ..default.clone()
            },
        ),
        (
            "volume_tolerance",
            InverseOptions {
                volume_tolerance: f64::NAN,
                ..default.clone()
            },
        ),
        (
            "volume_tolerance",
            InverseOptions {
                volume_tolerance: f64::INFINITY,
                ..default.clone()
            },
        ),
        (
            "max_runs",
            InverseOptions {
                max_runs: 0,
                ..default.clone()
            },
        ),
        (
            "max_runs",
            InverseOptions {
                max_runs: 1,
                ..default.clone()
            },
        ),
    ];
    let never = |_: f64| -> Result<f64, ImplantError> { panic!("the closure must not be run") };
    for (expected, options) in &bad_options {
        let result = volume_for_gain(30.0, (10.0, 400.0), options, never);
        assert!(
            matches!(result, Err(ImplantError::InvalidParameter { param, .. }) if param.name() == *expected),
            "{options:?}: {result:?}"
        );
    }

    let bad_brackets = [
        ("bracket.low", (0.0, 10.0)),
        ("bracket.low", (-1.0, 10.0)),
        ("bracket.low", (f64::NAN, 10.0)),
        ("bracket.low", (f64::NEG_INFINITY, 10.0)),
        ("bracket.high", (10.0, 10.0)),
        ("bracket.high", (10.0, 5.0)),
        ("bracket.high", (10.0, f64::NAN)),
        ("bracket.high", (10.0, f64::INFINITY)),
    ];
    for (expected, bracket) in bad_brackets {
        let result = volume_for_gain(30.0, bracket, &default, never);
        assert!(
            matches!(result, Err(ImplantError::InvalidParameter { param, .. }) if param.name() == expected),
            "{bracket:?}: {result:?}"
        );
    }

    for target in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let result = volume_for_gain(target, (10.0, 400.0), &default, never);
        assert!(
            matches!(
                result,
                Err(ImplantError::InvalidParameter {
                    param: Param::TargetGain,
                    ..
                })
            ),
            "{target}: {result:?}"
        );
    }

    // The smallest valid budget runs the two ends and stops.
    let two = InverseOptions {
        max_runs: 2,
        ..default
    };
    let found = volume_for_gain(30.0, (10.0, 400.0), &two, |v| Ok(sigmoid(v)));
    let found = found.unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(found.runs.len(), 2);
    assert!(!found.converged);
}

/// A deterministic but uneven amount of work per input, to shuffle the finishing order.
fn busy(input: &u64) -> Result<(u64, f64), ImplantError> {
    if input % 7 == 3 {
        return Err(ImplantError::Cancelled { steps: *input });
    }
    let mut x = *input as f64 * 0.1;
    for k in 0..(1000 + (input * 7919) % 20_000) {
        x = (x + (k as f64).sqrt()).sin() + *input as f64;
    }
    Ok((*input, x))
}

#[test]
fn sweep_keeps_input_order_and_is_thread_independent() -> Result<(), rayon::ThreadPoolBuildError> {
    let inputs: Vec<u64> = (0..200).rev().collect();
    let sequential: Vec<_> = inputs.iter().map(busy).collect();

    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let three = rayon::ThreadPoolBuilder::new().num_threads(3).build()?;
    let on_one = one.install(|| sweep(&inputs, busy));
    let on_three = three.install(|| sweep(&inputs, busy));
    let on_global = sweep(&inputs, busy);

    assert_eq!(on_one.len(), inputs.len());
    for (i, result) in on_three.iter().enumerate() {
        match result {
            Ok((input, _)) => assert_eq!(*input, inputs[i]),
            Err(e) => assert_eq!(*e, ImplantError::Cancelled { steps: inputs[i] }),
        }
    }
    // Bitwise identical, errors in place.
    assert_eq!(on_one, sequential);
    assert_eq!(on_three, sequential);
    assert_eq!(on_global, sequential);
    Ok(())
}

#[test]
fn sweep_of_nothing_is_empty() {
    let none: [f64; 0] = [];
    assert!(sweep(&none, |v: &f64| Ok(*v)).is_empty());
}

#[test]
fn sweep_runs_inverse_searches() {
    // A sweep over targets, each an inverse search: the two compose.
    let targets = [10.0, 20.0, 30.0, 40.0];
    let found = sweep(&targets, |&target: &f64| {
        volume_for_gain(target, (10.0, 400.0), &InverseOptions::default(), |v| {
            Ok(linear(v))
        })
    });
    for (target, result) in targets.iter().zip(&found) {
        let search = result.as_ref().unwrap_or_else(|e| panic!("{e}"));
        assert!((search.gain - target).abs() <= 0.5);
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(256))]

    /// On any power-law gain `a·V^p` (increasing or, with a < 0, decreasing) and any bracket and
    /// tolerances, the search converges to the known root, inside the bracket, and its runs are
    /// exactly the closure's calls.
    #[test]
    fn power_laws_are_solved(
        a in 0.01f64..10.0,
        decreasing in proptest::bool::ANY,
        p in 0.3f64..3.0,
        low in 1.0f64..50.0,
        span in 1.0f64..1000.0,
        at in 0.01f64..0.99,
        gain_tolerance in 1e-6f64..1.0,
        volume_tolerance in 1e-6f64..1.0,
    ) {
        let a = if decreasing { -a } else { a };
        let high = low + span;
        let root = low + at * span;
        let gain = |v: f64| a * v.powf(p);
        let target = gain(root);
        let options = InverseOptions { gain_tolerance, volume_tolerance, max_runs: 200 };
        let calls = RefCell::new(Vec::new());
        let found = volume_for_gain(target, (low, high), &options, |volume| {
            let g = gain(volume);
            calls.borrow_mut().push(PlanningRun { volume, gain: g });
            Ok(g)
        });
        let found = match found {
            Ok(found) => found,
            Err(e) => return Err(proptest::test_runner::TestCaseError::fail(e.to_string())),
        };
        proptest::prop_assert!(found.converged);
        proptest::prop_assert_eq!(&found.runs, &calls.into_inner());
        proptest::prop_assert!(found.runs.len() <= 40, "{} runs", found.runs.len());
        proptest::prop_assert!(found.runs.iter().all(|r| r.volume >= low && r.volume <= high));
        let answer = PlanningRun {
            volume: found.volume,
            gain: found.gain,
        };
        proptest::prop_assert!(found.runs.contains(&answer));
        // The gain is monotone: the answer is the run closest to the target.
        let best = found
            .runs
            .iter()
            .map(|r| (r.gain - target).abs())
            .fold(f64::INFINITY, f64::min);
        proptest::prop_assert_eq!((found.gain - target).abs(), best);
        let gain_ok = (found.gain - target).abs() <= gain_tolerance;
        let volume_ok = (found.volume - root).abs() <= volume_tolerance * (1.0 + 1e-9);
        proptest::prop_assert!(gain_ok || volume_ok, "{found:?}, root {root}, target {target}");
    }
}
