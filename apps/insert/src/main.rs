//! `insert`: plan a tissue-expander insertion on a patient's surface scan from the command line.
//!
//! A thin shell over the planning front door, tissue-planner: command line ([`cli`]) → the
//! planner's request and scenario ([`setup`]) → the events loop with progress and Ctrl-C
//! ([`progress`]) → stdout, the mesh, picture and JSON report ([`modes`], [`output`],
//! [`report`]: the tables on stdout; the JSON contract is the planner's). Every failure is one line on stderr and a documented exit code
//! ([`failure`]); see `insert --help` and `apps/insert/README.md`.
#![allow(clippy::print_stdout, clippy::print_stderr)]

mod cli;
mod failure;
mod modes;
mod output;
mod progress;
mod report;
mod setup;

use std::process::ExitCode;

use clap::Parser;
use tissue_planner::report::Inputs;

use crate::cli::Cli;
use crate::failure::{Exit, Failure};
use crate::progress::Interrupt;

fn run(cli: &Cli) -> Result<(), Failure> {
    let interrupt = Interrupt::install()?;
    output::check_targets(cli)?;
    let scenario = setup::scenario(cli)?;
    interrupt.check()?;
    let inputs = Inputs::new(&scenario).map_err(|e| Failure::from_plan(&e))?;
    if let Some(volumes) = &cli.sweep {
        modes::sweep(cli, &scenario, &inputs, volumes, &interrupt)
    } else if cli.expand_weeks.is_some() {
        modes::expansion(cli, &scenario, &inputs, &interrupt)
    } else if let Some(target) = cli.target_gain {
        modes::target_gain(cli, &scenario, &inputs, target, &interrupt)
    } else {
        modes::single(cli, &scenario, &inputs, &interrupt)
    }
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
