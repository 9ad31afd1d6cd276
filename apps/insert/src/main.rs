//! `insert`: plan a tissue-expander insertion on a patient's surface scan from the command line.
//!
//! A thin shell over the planning front door, tissue-planner: the command line ([`cli`]) makes
//! the planner's [`JobSpec`](tissue_planner::JobSpec) (`Cli::job_spec`, the same JSON shape the
//! studio and the C ABI take) and the patient ([`setup`]); the planner runs and finishes the job
//! ([`tissue_planner::PlannedJob::run`]) with the progress display and Ctrl-C ([`progress`]);
//! then the tables on stdout ([`report`]) and the outputs, written together ([`output`]).
//! Every failure is one line on stderr and a documented exit code ([`failure`]); see
//! `insert --help` and `apps/insert/README.md`.
#![allow(clippy::print_stdout, clippy::print_stderr)]

mod cli;
mod failure;
mod output;
mod progress;
mod report;
mod save;
mod setup;

use std::process::ExitCode;

use clap::Parser;
use tissue_planner::{Finished, JobMode, JobReport, Stopped, Tool};

use crate::cli::Cli;
use crate::failure::{Exit, Failure, FromPlan};
use crate::output::Staged;
use crate::progress::{Display, Interrupt};
use crate::save::Saving;

fn run(cli: &Cli) -> Result<(), Failure> {
    let interrupt = Interrupt::install()?;
    output::check_targets(cli)?;
    let spec = cli.job()?;
    if spec.mode != JobMode::Single && (!cli.out.is_empty() || cli.png.is_some()) {
        return Err(Failure::new(
            Exit::Usage,
            format!(
                "--out and --png are a single run's (the patient after it); this job is a {} run",
                spec.mode.name()
            ),
        ));
    }
    // The numbers are checked before the file is read: a typo costs no load.
    spec.check().map_err(|e| Failure::from_plan(&e))?;
    // So are the plan's name and the library of --save: a typo or an unusable --data costs no run.
    let saving = Saving::prepare(cli)?;
    let scenario = setup::scenario(cli, &spec)?;
    let scan = match &saving {
        Some(_) => Some(Saving::scan(cli, &scenario)?),
        None => None,
    };
    interrupt.check()?;
    let planned = spec.plan(&scenario).map_err(|e| Failure::from_plan(&e))?;
    let mut display = Display::new(cli.quiet, spec.mode != JobMode::Single);
    let finished = planned.run(&scenario, Tool::Insert, interrupt.token(), |p| {
        display.progress(p);
    });
    display.finish();
    let finished = finished.map_err(|stopped| match stopped {
        Stopped::Cancelled { steps } => Failure::interrupted(steps),
        Stopped::Failed(e) => Failure::from_plan(&e),
    })?;
    print!("{}", report::stdout(&finished));
    for warning in report::warnings(&finished) {
        eprintln!("insert: warning: {warning}");
    }
    let staged = stage(cli, &scenario, &finished)?;
    for path in staged.commit(&interrupt)? {
        eprintln!("insert: wrote {}", path.display());
    }
    // The plan is saved after the outputs, in one transaction; Ctrl-C only sets the token, so
    // the process does not end in the middle of it.
    if let (Some(saving), Some(scan)) = (&saving, &scan) {
        let plan = saving.save(scan, &spec, &finished)?;
        eprintln!(
            "insert: saved plan {} {:?} for patient {} in {}",
            plan.uid,
            plan.name,
            plan.patient_uid,
            saving.database_path().display()
        );
    }
    Ok(())
}

/// The outputs the command line asked for, staged beside their targets.
fn stage(
    cli: &Cli,
    scenario: &tissue_planner::Scenario,
    finished: &Finished,
) -> Result<Staged, Failure> {
    let mut staged = Staged::default();
    if let Some(patient) = &finished.patient {
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
        let json = finished
            .report
            .to_json()
            .map_err(|e| Failure::from_plan(&e))?;
        staged.bytes(path, json.as_bytes(), "report")?;
    }
    if let (Some(path), JobReport::Expansion(report)) = (&cli.chart, &finished.report) {
        let bytes = report
            .chart(cli.png_size)
            .map_err(|e| Failure::from_plan(&e))?;
        staged.bytes(path, &bytes, "chart")?;
    }
    Ok(staged)
}

/// Where the demo (no arguments at all) puts its picture.
const DEMO_PICTURE: &str = "insert_table2.png";

fn main() -> ExitCode {
    // A closed stdout (`| head`) ends the program by SIGPIPE, silently; see tissue-cli.
    tissue_cli::reset_sigpipe();
    let mut cli = Cli::parse();
    // With no arguments at all the program is the demo of the README: Table 2 with a picture.
    let demo = std::env::args_os().len() <= 1;
    if demo {
        cli.png = Some(DEMO_PICTURE.into());
    }
    match run(&cli) {
        Ok(()) => {
            if demo {
                println!(
                    "  picture              {DEMO_PICTURE} (before and after, by displacement)"
                );
            }
            ExitCode::SUCCESS
        }
        Err(failure) => {
            let hint = if failure.code == Exit::Usage {
                " (see insert --help)"
            } else {
                ""
            };
            eprintln!("insert: error: {}{hint}", failure.line());
            ExitCode::from(failure.code)
        }
    }
}
