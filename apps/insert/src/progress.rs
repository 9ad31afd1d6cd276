//! Driving a tissue-app job: the events loop, the progress display on stderr (bars on a
//! terminal, plain lines otherwise) and Ctrl-C, which cancels through the handle.

use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use tissue_planner::{Event, Handle, Job, Outcome, ProgressEvent};

use crate::failure::{Exit, Failure};

/// Set by Ctrl-C (SIGINT); read by the events loop and before outputs are committed.
#[derive(Debug, Clone)]
pub struct Interrupt(Arc<AtomicBool>);

impl Interrupt {
    /// Installs the Ctrl-C handler.
    ///
    /// # Errors
    /// When the handler cannot be installed.
    pub fn install() -> Result<Self, Failure> {
        let flag = Arc::new(AtomicBool::new(false));
        let set = Arc::clone(&flag);
        ctrlc::set_handler(move || set.store(true, Ordering::SeqCst)).map_err(|e| {
            Failure::new(Exit::Run, format!("cannot install the Ctrl-C handler: {e}"))
        })?;
        Ok(Interrupt(flag))
    }

    /// Whether Ctrl-C was pressed.
    pub fn is_set(&self) -> bool {
        self.0.load(Ordering::SeqCst)
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

/// Runs `job` on a tissue-app worker, showing its progress, cancelling it on Ctrl-C.
///
/// # Errors
/// [`Failure::interrupted`] (exit 130) when cancelled, the job's failure otherwise.
pub fn drive(job: Job, display: &mut Display, interrupt: &Interrupt) -> Result<Outcome, Failure> {
    let mut handle = Handle::start(job);
    let terminal = loop {
        if interrupt.is_set() && !handle.is_cancelled() {
            handle.cancel();
        }
        match handle.recv_timeout(Duration::from_millis(50)) {
            Some(Event::Progress(p)) => display.progress(&p),
            Some(terminal) => break terminal,
            None => {}
        }
    };
    display.finish();
    match terminal {
        Event::Finished(outcome) => Ok(outcome),
        Event::Cancelled { steps } => Err(Failure::interrupted(steps)),
        Event::Failed(e) => Err(Failure::from_plan(&tissue_planner::PlanError::from_app(&e))),
        Event::Progress(_) => Err(Failure::new(Exit::Run, "the worker ended without a result")),
    }
}
