//! The progress display on stderr (bars on a terminal, plain lines otherwise), fed by the
//! planner's progress callback, and Ctrl-C, which cancels the job through its token.

use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use tissue_planner::{CancelToken, ProgressEvent};

use crate::failure::{Exit, Failure};

/// Set by Ctrl-C (SIGINT): the job's cancel token, read again before outputs are committed.
#[derive(Debug, Clone)]
pub struct Interrupt(CancelToken);

impl Interrupt {
    /// Installs the Ctrl-C handler.
    ///
    /// # Errors
    /// When the handler cannot be installed.
    pub fn install() -> Result<Self, Failure> {
        let token = CancelToken::new();
        let set = token.clone();
        ctrlc::set_handler(move || set.cancel()).map_err(|e| {
            Failure::new(Exit::Run, format!("cannot install the Ctrl-C handler: {e}"))
        })?;
        Ok(Interrupt(token))
    }

    /// The token a job runs with: Ctrl-C cancels it.
    pub fn token(&self) -> &CancelToken {
        &self.0
    }

    /// Whether Ctrl-C was pressed.
    pub fn is_set(&self) -> bool {
        self.0.is_cancelled()
    }

    /// `Err(interrupted)` once Ctrl-C was pressed.
    pub fn check(&self) -> Result<(), Failure> {
        if self.is_set() {
            Err(Failure::interrupted(0))
        } else {
            Ok(())
        }
    }
}

/// How progress is shown.
#[derive(Debug)]
enum Mode {
    /// Nothing (`--quiet`).
    Quiet,
    /// indicatif bars, one per run.
    Bars {
        multi: MultiProgress,
        bars: BTreeMap<usize, ProgressBar>,
    },
    /// A line at the first step, then every second or every tenth of the step limit.
    Plain {
        last: BTreeMap<usize, (Instant, u64)>,
    },
}

/// The progress display of one job.
#[derive(Debug)]
pub struct Display {
    mode: Mode,
    /// Label runs ("run 2") — for jobs of several runs.
    label_runs: bool,
}

impl Display {
    /// Bars when stderr is a terminal, plain lines otherwise, nothing when `quiet`.
    pub fn new(quiet: bool, label_runs: bool) -> Self {
        let mode = if quiet {
            Mode::Quiet
        } else if std::io::stderr().is_terminal() {
            Mode::Bars {
                multi: MultiProgress::with_draw_target(ProgressDrawTarget::stderr()),
                bars: BTreeMap::new(),
            }
        } else {
            Mode::Plain {
                last: BTreeMap::new(),
            }
        };
        Display { mode, label_runs }
    }

    fn label(&self, run: usize) -> String {
        if self.label_runs {
            format!("run {}", run + 1)
        } else {
            "insert".to_owned()
        }
    }

    /// Shows one step.
    pub fn progress(&mut self, p: &ProgressEvent) {
        let label = self.label(p.run);
        match &mut self.mode {
            Mode::Quiet => {}
            Mode::Bars { multi, bars } => {
                let bar = bars.entry(p.run).or_insert_with(|| {
                    let bar = multi.add(ProgressBar::new(p.max_steps));
                    let style = ProgressStyle::with_template(
                        "{prefix:>8} [{bar:32.cyan/blue}] step {pos}/{len}  settle {msg}  {elapsed}",
                    )
                    .unwrap_or_else(|_| ProgressStyle::default_bar())
                    .progress_chars("=> ");
                    bar.set_style(style);
                    bar.set_prefix(label);
                    bar
                });
                bar.set_length(p.max_steps);
                bar.set_position(p.step);
                match p.day {
                    Some(day) => bar.set_message(format!("day {day:.1}")),
                    None => bar.set_message(format!("{:>3.0}%", 100.0 * p.settle)),
                }
            }
            Mode::Plain { last } => {
                let tenth = (p.max_steps / 10).max(1);
                let decile = p.step / tenth;
                let now = Instant::now();
                let due = match last.get(&p.run) {
                    None => true,
                    Some(&(at, d)) => {
                        decile > d || now.duration_since(at) >= Duration::from_secs(1)
                    }
                };
                if due && p.day.is_some() {
                    last.insert(p.run, (now, decile));
                    eprintln!(
                        "{label}: day {:.1}, settle step {}/{}, {:.1} s",
                        p.day.unwrap_or(0.0),
                        p.step,
                        p.max_steps,
                        p.elapsed.as_secs_f64()
                    );
                } else if due {
                    last.insert(p.run, (now, decile));
                    eprintln!(
                        "{label}: step {}/{}, settle {:.0}%, {:.1} s",
                        p.step,
                        p.max_steps,
                        100.0 * p.settle,
                        p.elapsed.as_secs_f64()
                    );
                }
            }
        }
    }

    /// Ends the display: bars stay on screen with their last state.
    pub fn finish(&mut self) {
        if let Mode::Bars { bars, .. } = &mut self.mode {
            for bar in bars.values() {
                bar.abandon();
            }
        }
    }
}
