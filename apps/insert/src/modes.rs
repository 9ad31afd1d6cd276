//! The three things `insert` does — one run, a sweep of volumes, the search for a target area
//! gain — each as: a tissue-app job, its events loop, then the outputs and stdout.

use tissue_app::{InverseJob, Job, Outcome, SweepJob};
use tissue_implant::InverseOptions;

use crate::cli::Cli;
use crate::failure::{code, Failure};
use crate::output::{PatientResult, Staged};
use crate::progress::{drive, Display, Interrupt};
use crate::report::{self, Inputs, RunResult, SweepRow};
use crate::setup::Scenario;

fn unexpected(outcome: &Outcome) -> Failure {
    Failure::new(
        code::RUN,
        format!("the worker returned an unexpected result: {outcome:?}"),
    )
}

fn json(value: &impl serde::Serialize) -> Result<Vec<u8>, Failure> {
    let mut text = serde_json::to_string_pretty(value).map_err(|e| Failure::output("report", e))?;
    text.push('\n');
    Ok(text.into_bytes())
}

/// Commits the staged outputs and says what was written.
fn commit(staged: Staged, interrupt: &Interrupt) -> Result<(), Failure> {
    for path in staged.commit(interrupt)? {
        eprintln!("insert: wrote {}", path.display());
    }
    Ok(())
}

fn warn_step_limit(r: &RunResult, what: &str) {
    if r.stop_reason != "settled" {
        eprintln!(
            "insert: warning: {what} reached the step limit ({}) before the tissue settled; \
             the results are not at rest: raise --max-steps",
            r.max_steps
        );
    }
}

/// One insertion: summary on stdout, then `--out`, `--png`, `--report`.
pub fn single(
    cli: &Cli,
    scenario: &Scenario,
    inputs: &Inputs,
    interrupt: &Interrupt,
) -> Result<(), Failure> {
    let max_steps = scenario.job.params.run.stop.max_steps;
    let mut display = Display::new(cli.quiet, false);
    let outcome = drive(
        Job::Insertion(scenario.job.clone()),
        &mut display,
        interrupt,
    )?;
    let planned = match outcome {
        Outcome::Insertion(p) => *p,
        other => return Err(unexpected(&other)),
    };
    if !planned.outcome.is_finite() {
        return Err(Failure::new(
            code::RUN,
            "the run diverged: the result has positions that are not finite; leave --time-step \
             automatic, or lower it",
        ));
    }
    // On a remeshed run the result is mapped onto the scan for the report's scan figures too.
    let patient = if !cli.out.is_empty() || cli.png.is_some() || planned.surface.is_some() {
        Some(PatientResult::new(scenario, &planned)?)
    } else {
        None
    };
    let result = RunResult::of(
        &planned,
        patient.as_ref().and_then(|p| p.scan.as_ref()),
        max_steps,
    );
    print!("{}", report::summary(inputs, &result));
    warn_step_limit(&result, "the run");

    let mut staged = Staged::default();
    if let Some(patient) = &patient {
        for out in &cli.out {
            staged.mesh(out, &patient.after, &patient.fields())?;
        }
        if let Some(png) = &cli.png {
            let bytes = patient.picture(cli.color, cli.png_size, scenario.unit.symbol())?;
            staged.bytes(png, &bytes, "picture")?;
        }
    }
    if let Some(path) = &cli.report {
        let bytes = json(&report::single(inputs.clone(), result))?;
        staged.bytes(path, &bytes, "report")?;
    }
    commit(staged, interrupt)
}

/// A series of volumes in parallel: one row per run on stdout, then `--report`.
pub fn sweep(
    cli: &Cli,
    scenario: &Scenario,
    inputs: &Inputs,
    volumes: &[f64],
    interrupt: &Interrupt,
) -> Result<(), Failure> {
    let max_steps = scenario.job.params.run.stop.max_steps;
    let job = SweepJob {
        base: scenario.job.clone(),
        volumes: volumes.to_vec(),
    };
    let mut display = Display::new(cli.quiet, true);
    let result = match drive(Job::Sweep(job), &mut display, interrupt)? {
        Outcome::Sweep(s) => *s,
        other => return Err(unexpected(&other)),
    };
    println!("{}", report::SWEEP_HEADER);
    let mut rows = Vec::new();
    let mut failure = None;
    for run in &result.runs {
        match &run.result {
            Ok(outcome) if outcome.is_finite() => {
                let r = RunResult::new(
                    outcome,
                    &result.selection,
                    result.surface.as_ref(),
                    max_steps,
                );
                println!("{}", report::sweep_row(run.volume, &r));
                warn_step_limit(&r, &format!("the {} cm³ run", run.volume));
                rows.push(SweepRow {
                    volume_cm3: run.volume,
                    result: r,
                });
            }
            Ok(_) => {
                let f = Failure::new(code::RUN, "the run diverged (positions not finite)");
                println!("{}", report::sweep_failed_row(run.volume, &f.line()));
                failure.get_or_insert(f);
            }
            Err(e) => {
                let f = Failure::from_implant(e);
                println!("{}", report::sweep_failed_row(run.volume, &f.line()));
                failure.get_or_insert(f);
            }
        }
    }
    if let Some(f) = failure {
        return Err(Failure::new(
            f.code,
            format!(
                "a run of the sweep failed, nothing was written: {}",
                f.message
            ),
        ));
    }
    let mut staged = Staged::default();
    if let Some(path) = &cli.report {
        let bytes = json(&report::sweep(inputs.clone(), &result, rows))?;
        staged.bytes(path, &bytes, "report")?;
    }
    commit(staged, interrupt)
}

/// The volume for a target area gain: every run and the answer on stdout, then `--report`.
pub fn target_gain(
    cli: &Cli,
    scenario: &Scenario,
    inputs: &Inputs,
    target: f64,
    interrupt: &Interrupt,
) -> Result<(), Failure> {
    let bracket = cli.bracket.unwrap_or((
        0.25 * scenario.job.implant.volume_cm3,
        2.0 * scenario.job.implant.volume_cm3,
    ));
    let job = InverseJob {
        base: scenario.job.clone(),
        target_gain: target,
        bracket,
        options: InverseOptions {
            gain_tolerance: cli.gain_tolerance,
            ..InverseOptions::default()
        },
    };
    let mut display = Display::new(cli.quiet, true);
    let search = match drive(Job::Inverse(job), &mut display, interrupt)? {
        Outcome::Inverse(s) => s,
        other => return Err(unexpected(&other)),
    };
    println!("run  volume cm³  area gain cm²");
    for (i, run) in search.runs.iter().enumerate() {
        println!("{:>3}  {:>10.4}  {:>13.4}", i + 1, run.volume, run.gain);
    }
    println!(
        "answer: {:.4} cm³ gives an area gain of {:.4} cm² (target {target} cm², {} runs, {})",
        search.volume,
        search.gain,
        search.runs.len(),
        if search.converged {
            "converged"
        } else {
            "not converged: the run budget ran out, best estimate"
        }
    );
    let mut staged = Staged::default();
    if let Some(path) = &cli.report {
        let bytes = json(&report::inverse(inputs.clone(), target, bracket, &search))?;
        staged.bytes(path, &bytes, "report")?;
    }
    commit(staged, interrupt)
}
