//! The three things `insert` does — one run, a sweep of volumes, the search for a target area
//! gain — each as: a tissue-app job, its events loop, then the outputs and stdout.

use tissue_planner::report::{self as contract, Inputs, RunResult};
use tissue_planner::{Job, Outcome, PatientResult, Scenario};

use crate::cli::Cli;
use crate::failure::{Exit, Failure};
use crate::output::Staged;
use crate::progress::{drive, Display, Interrupt};
use crate::report;

/// The report's `tool`.
const TOOL: &str = "insert";

fn unexpected(outcome: &Outcome) -> Failure {
    Failure::new(
        Exit::Run,
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
            Exit::Run,
            "the run diverged: the result has positions that are not finite; leave --time-step \
             automatic, or lower it",
        ));
    }
    // On a remeshed run the result is mapped onto the scan for the report's scan figures too.
    let patient = if !cli.out.is_empty() || cli.png.is_some() || planned.surface.is_some() {
        Some(PatientResult::new(scenario, &planned).map_err(|e| Failure::from_plan(&e))?)
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
            staged.mesh(out, patient)?;
        }
        if let Some(png) = &cli.png {
            let bytes = patient
                .picture(cli.color, cli.png_size, scenario.patient.unit.symbol())
                .map_err(|e| Failure::from_plan(&e))?;
            staged.bytes(png, &bytes, "picture")?;
        }
    }
    if let Some(path) = &cli.report {
        let bytes = json(&contract::single(TOOL, inputs.clone(), result))?;
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
    let job = scenario
        .sweep_job(volumes)
        .map_err(|e| Failure::from_plan(&e))?;
    let mut display = Display::new(cli.quiet, true);
    let result = match drive(Job::Sweep(job), &mut display, interrupt)? {
        Outcome::Sweep(s) => *s,
        other => return Err(unexpected(&other)),
    };
    println!("{}", report::SWEEP_HEADER);
    let mut rows = Vec::new();
    let mut failure = None;
    for (volume, row) in contract::sweep_rows(&result, max_steps) {
        match row {
            Ok(row) => {
                println!("{}", report::sweep_row(volume, &row.result));
                warn_step_limit(&row.result, &format!("the {volume} cm³ run"));
                rows.push(row);
            }
            Err(e) => {
                let f = Failure::from_plan(&e);
                println!("{}", report::sweep_failed_row(volume, &f.line()));
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
        let bytes = json(&contract::sweep(TOOL, inputs.clone(), &result, rows))?;
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
    let job = scenario
        .inverse_job(target, cli.bracket, cli.gain_tolerance)
        .map_err(|e| Failure::from_plan(&e))?;
    let bracket = job.bracket;
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
        let bytes = json(&contract::inverse(
            TOOL,
            inputs.clone(),
            target,
            bracket,
            &search,
        ))?;
        staged.bytes(path, &bytes, "report")?;
    }
    commit(staged, interrupt)
}

/// An expansion over weeks: the weekly figures and the flap on stdout, then `--report`,
/// `--chart`.
pub fn expansion(
    cli: &Cli,
    scenario: &Scenario,
    inputs: &Inputs,
    interrupt: &Interrupt,
) -> Result<(), Failure> {
    let job = scenario
        .expansion_job()
        .map_err(|e| Failure::from_plan(&e))?
        .ok_or_else(|| Failure::new(Exit::Usage, "--expand-weeks is required"))?;
    let mut display = Display::new(cli.quiet, true);
    let planned = match drive(
        Job::Expansion(Box::new(job.clone())),
        &mut display,
        interrupt,
    )? {
        Outcome::Expansion(p) => *p,
        other => return Err(unexpected(&other)),
    };
    let report = contract::expansion(TOOL, inputs.clone(), &scenario.request, &job, &planned);
    print!("{}", report::expansion_summary(&report));
    let mut staged = Staged::default();
    if let Some(path) = &cli.report {
        staged.bytes(path, &json(&report)?, "report")?;
    }
    if let Some(path) = &cli.chart {
        let bytes = report
            .chart(cli.png_size)
            .map_err(|e| Failure::from_plan(&e))?;
        staged.bytes(path, &bytes, "chart")?;
    }
    commit(staged, interrupt)
}
