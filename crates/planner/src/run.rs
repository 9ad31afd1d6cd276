//! The output side of the front door: a planned job run to its end and finished into its report
//! and results, the same for every front end.
//!
//! [`PlannedJob::run`] runs the job on tissue-app's worker (blocking, progress handed to a
//! callback on the calling thread, cancelled through a [`CancelToken`]); [`finish`]
//! turns the worker's [`Outcome`] into a [`Finished`] job: its [`JobReport`], the deformed
//! patient of a single run, and a sweep's runs in order. Here, and only here:
//! - **divergence** is checked (positions not finite: [`report::diverged`], one message);
//! - **the sweep policy** is applied: a sweep reports the runs that ran and lists the failed
//!   ones in `failed_runs`; it fails as a whole only when no run ran.

use tissue_app::{CancelToken, Handle, HandleOptions, Outcome, ProgressEvent};

use crate::error::{ErrorKind, PlanError};
use crate::job::{JobKind, PlannedJob};
use crate::report::{self, Inputs, JobReport, RunResult, Tool};
use crate::result::PatientResult;
use crate::scenario::Scenario;

/// A finished job: its report and what a front end shows or writes besides.
#[derive(Debug, Clone)]
pub struct Finished {
    /// The report (the JSON contract).
    pub report: JobReport,
    /// A single run's deformed patient with its fields, in the file's unit (`None` for the
    /// other modes).
    pub patient: Option<PatientResult>,
    /// A sweep's runs in the order given: figures, or why there are none (empty for the other
    /// modes).
    pub sweep: report::SweepOutcomes,
}

/// How a job ended without a result.
#[derive(Debug, Clone, PartialEq)]
pub enum Stopped {
    /// Cancelled through its token, after this many steps (summed over its runs).
    Cancelled {
        /// Steps done.
        steps: u64,
    },
    /// Refused or failed.
    Failed(PlanError),
}

impl From<PlanError> for Stopped {
    fn from(e: PlanError) -> Self {
        Stopped::Failed(e)
    }
}

impl From<Stopped> for PlanError {
    /// A cancel as [`ErrorKind::Cancelled`].
    fn from(s: Stopped) -> Self {
        match s {
            Stopped::Cancelled { steps } => PlanError::cancelled(steps),
            Stopped::Failed(e) => e,
        }
    }
}

impl PlannedJob {
    /// Runs the job on tissue-app's worker to its end and finishes it ([`finish`]).
    /// Blocks; `on_progress` is called on this thread for each progress event (some are
    /// dropped while it is slow; the run never waits for it). `cancel` (cancelled from any
    /// thread) ends the job within one step.
    ///
    /// # Errors
    /// [`Stopped::Cancelled`] with the steps done, or [`Stopped::Failed`] with the run's or
    /// the finish's error.
    pub fn run(
        self,
        scenario: &Scenario,
        tool: Tool,
        cancel: &CancelToken,
        on_progress: impl FnMut(&ProgressEvent),
    ) -> Result<Finished, Stopped> {
        let PlannedJob { job, kind, .. } = self;
        let handle = Handle::start_cancellable(job, HandleOptions::default(), cancel.clone());
        let outcome = handle
            .run(on_progress)
            .map_err(|e| match e.cancelled_steps() {
                Some(steps) => Stopped::Cancelled { steps },
                None => Stopped::Failed(PlanError::from_app(&e)),
            })?;
        Ok(finish(&kind, outcome, scenario, tool)?)
    }
}

/// Finishes a job of `kind` from the worker's `outcome`: the report, the deformed patient of a
/// single run, a sweep's runs.
///
/// # Errors
/// [`ErrorKind::Run`] for a diverged single run ([`report::diverged`]) or a failed mapping onto
/// the patient; a sweep's first error when no run ran; [`ErrorKind::Run`] for an outcome that is
/// not the kind's (a bug).
pub fn finish(
    kind: &JobKind,
    outcome: Outcome,
    scenario: &Scenario,
    tool: Tool,
) -> Result<Finished, PlanError> {
    let _span = tracing::info_span!("planner_finish").entered();
    let inputs = Inputs::new(scenario)?;
    let max_steps = scenario.job.params.run.stop.max_steps;
    let only = |report| Finished {
        report,
        patient: None,
        sweep: Vec::new(),
    };
    match (outcome, kind) {
        (Outcome::Insertion(planned), JobKind::Single) => {
            if !planned.outcome.is_finite() {
                return Err(report::diverged());
            }
            let patient = PatientResult::new(scenario, &planned)?;
            let result = RunResult::of(&planned, patient.scan.as_ref(), max_steps);
            Ok(Finished {
                report: JobReport::Single(report::single(tool, inputs, result)),
                patient: Some(patient),
                sweep: Vec::new(),
            })
        }
        (Outcome::Sweep(sweep), JobKind::Sweep) => {
            let (report, runs) = report::sweep(tool, inputs, &sweep, max_steps)?;
            Ok(Finished {
                report: JobReport::Sweep(report),
                patient: None,
                sweep: runs,
            })
        }
        (Outcome::Inverse(found), JobKind::TargetGain { target, bracket }) => Ok(only(
            JobReport::TargetGain(report::inverse(tool, inputs, *target, *bracket, &found)),
        )),
        (Outcome::Expansion(planned), JobKind::Expansion(job)) => Ok(only(JobReport::Expansion(
            report::expansion(tool, inputs, &scenario.request, job, &planned),
        ))),
        (other, kind) => Err(PlanError::new(
            ErrorKind::Run,
            format!(
                "the worker returned {other:?} for a {kind:?} job; this is a bug, please report it"
            ),
        )),
    }
}

#[cfg(test)]
#[allow(clippy::panic)]
mod tests {
    use super::*;
    use crate::{JobSpec, Patient, Shipped};

    fn run(json: &str) -> Result<Finished, Stopped> {
        let spec: JobSpec = serde_json::from_str(json)
            .map_err(|e| PlanError::new(ErrorKind::Usage, e.to_string()))?;
        let scenario = Scenario::new(Patient::shipped(Shipped::Table2)?, spec.request.clone())?;
        spec.plan(&scenario)?
            .run(&scenario, Tool::Insert, &CancelToken::new(), |_| {})
    }

    /// The sweep policy: a volume the implant's base cannot hold fails its own run only; the
    /// report keeps the others and lists it, by volume, with its field; with no run left the
    /// job fails with that error.
    #[test]
    fn a_sweep_reports_its_failed_runs_and_fails_only_when_none_ran() -> Result<(), Stopped> {
        let finished =
            run(r#"{"mode": "sweep", "volumes_cm3": [20, 4000], "request": {"max_steps": 60}}"#)?;
        let JobReport::Sweep(report) = &finished.report else {
            return Err(PlanError::new(ErrorKind::Run, "not a sweep report").into());
        };
        assert_eq!(report.body.runs.len(), 1);
        assert_eq!(report.body.runs[0].volume_cm3, 20.0);
        assert_eq!(report.body.failed_runs.len(), 1);
        let failed = &report.body.failed_runs[0];
        assert_eq!(failed.volume_cm3, 4000.0);
        assert_eq!(failed.error.kind, ErrorKind::Parameters);
        assert_eq!(failed.error.field, Some("volume_cm3"));
        assert_eq!(finished.sweep.len(), 2, "every run, in order");
        assert!(finished.sweep[0].1.is_ok() && finished.sweep[1].1.is_err());
        let json = report::JobReport::Sweep(report.clone()).to_value()?;
        assert_eq!(json["failed_runs"][0]["error"]["field"], "volume_cm3");
        assert_eq!(
            json["inputs"]["sweep_volumes_cm3"],
            serde_json::json!([20.0, 4000.0])
        );

        let none = run(r#"{"mode": "sweep", "volumes_cm3": [4000, 4500]}"#).err();
        match none {
            Some(Stopped::Failed(e)) => {
                assert_eq!(e.field, Some("volume_cm3"));
                assert!(
                    e.message.starts_with("every run of the sweep failed"),
                    "{e}"
                );
            }
            other => panic!("a sweep with no run that ran: {other:?}"),
        }
        Ok(())
    }

    /// The request's solver reaches every mode's runs and report: `inputs.solver` in each,
    /// and every run's `iterations` (the explicit solver's steps) and `residual_n` (null for
    /// it) in a single run, a sweep's rows and a search's runs.
    #[test]
    fn every_mode_reports_its_solver_and_every_runs_iterations() -> Result<(), Stopped> {
        let value = |finished: &Finished| finished.report.to_value();
        for solver in crate::Solver::ALL {
            let name = solver.name();
            let single = value(&run(&format!(
                r#"{{"request": {{"solver": "{name}", "max_steps": 12}}}}"#
            ))?)?;
            assert_eq!(single["inputs"]["solver"], name);
            assert_eq!(single["iterations"], 12, "{name}");
            assert!(single.get("residual_n").is_some(), "{name}");

            let sweep = value(&run(&format!(
                r#"{{"mode": "sweep", "volumes_cm3": [20, 30],
                    "request": {{"solver": "{name}", "max_steps": 10}}}}"#
            ))?)?;
            assert_eq!(sweep["inputs"]["solver"], name);
            let rows = sweep["runs"].as_array().map_or(0, Vec::len);
            assert_eq!(rows, 2, "{sweep}");
            for i in 0..rows {
                assert_eq!(sweep["runs"][i]["iterations"], 10, "{name}");
                assert!(sweep["runs"][i].get("residual_n").is_some(), "{name}");
            }

            // Both ends are within the (wide) tolerance: two runs, the search's figures.
            let search = value(&run(&format!(
                r#"{{"mode": "target-gain", "target_gain_cm2": 0, "gain_tolerance_cm2": 1000,
                    "bracket_cm3": [20, 30], "request": {{"solver": "{name}", "max_steps": 8}}}}"#
            ))?)?;
            assert_eq!(search["inputs"]["solver"], name);
            let runs = search["runs"].as_array().map_or(0, Vec::len);
            assert_eq!(runs, 2, "{search}");
            for i in 0..runs {
                assert_eq!(search["runs"][i]["iterations"], 8, "{name}");
                assert!(search["runs"][i].get("residual_n").is_some(), "{name}");
            }
        }
        // Asked for, the explicit solver has no residual anywhere.
        let explicit = value(&run(
            r#"{"mode": "sweep", "volumes_cm3": [20], "request": {"solver": "explicit", "max_steps": 6}}"#,
        )?)?;
        assert!(explicit["runs"][0]["residual_n"].is_null(), "{explicit}");
        // An expansion runs with it too and says so.
        let expansion = value(&run(
            r#"{"mode": "expansion", "request": {"solver": "explicit", "expand_weeks": 1,
                "band_samples": 0, "growth_step_h": 24, "max_steps": 6}}"#,
        )?)?;
        assert_eq!(expansion["inputs"]["solver"], "explicit");
        Ok(())
    }

    /// A cancelled token ends the job as cancelled, not failed.
    #[test]
    fn a_cancelled_token_stops_the_job() -> Result<(), PlanError> {
        let scenario = Scenario::new(Patient::shipped(Shipped::Table2)?, Default::default())?;
        let token = CancelToken::new();
        token.cancel();
        let planned = JobSpec::default().plan(&scenario)?;
        let stopped = planned.run(&scenario, Tool::Studio, &token, |_| {}).err();
        assert_eq!(stopped, Some(Stopped::Cancelled { steps: 0 }));
        Ok(())
    }

    /// A diverged single run fails as a run error naming the time step (whether the library
    /// saw it during the run or the finish found positions that are not finite).
    #[test]
    fn a_diverged_run_fails_as_a_run_error_naming_the_time_step() -> Result<(), Stopped> {
        let e = run(r#"{"request": {"time_step_s": 0.005, "max_steps": 400}}"#).err();
        match e {
            Some(Stopped::Failed(e)) => {
                assert_eq!((e.kind, e.field), (ErrorKind::Run, Some("time_step_s")));
                assert!(e.message.contains("diverged"), "{e}");
            }
            other => panic!("a run at 0.005 s should diverge: {other:?}"),
        }
        Ok(())
    }
}
