//! `mode: "sweep"`: the insertion at each of several volumes, with the runs that failed.

use serde::Serialize;
use tissue_app::SweepResult;

use super::{diverged, Inputs, Report, RunResult, Tool};
use crate::error::PlanError;
use crate::job::JobMode;

/// `mode: "sweep"`: the envelope, `runs` and `failed_runs`.
pub type SweepReport = Report<SweepBody>;

/// One run of a sweep.
#[derive(Debug, Clone, Serialize)]
pub struct SweepRow {
    /// The implant volume run, cm³.
    pub volume_cm3: f64,
    /// Its results.
    #[serde(flatten)]
    pub result: RunResult,
}

/// A volume of a sweep whose run failed or diverged.
#[derive(Debug, Clone, Serialize)]
pub struct FailedRun {
    /// The implant volume, cm³.
    pub volume_cm3: f64,
    /// Why it has no results: `kind`, `field` (the request field at fault) and `message`.
    pub error: PlanError,
}

/// A sweep's results.
#[derive(Debug, Clone, Serialize)]
pub struct SweepBody {
    /// One row per volume that ran, in the order given.
    pub runs: Vec<SweepRow>,
    /// The volumes whose run failed, in the order given (empty when every run ran).
    pub failed_runs: Vec<FailedRun>,
}

/// Every run of a sweep in the order given: its figures, or why it has none.
pub type SweepOutcomes = Vec<(f64, Result<RunResult, PlanError>)>;

/// The sweep report, and every run in the order given.
///
/// # Errors
/// The first run's error when every run failed: a sweep with no result is a failed job.
pub(crate) fn sweep(
    tool: Tool,
    mut inputs: Inputs,
    result: &SweepResult,
    max_steps: u64,
) -> Result<(SweepReport, SweepOutcomes), PlanError> {
    inputs.sweep_volumes_cm3 = Some(result.runs.iter().map(|r| r.volume).collect());
    let outcomes: SweepOutcomes = result
        .runs
        .iter()
        .map(|run| {
            let row = match &run.result {
                Ok(outcome) if outcome.is_finite() => Ok(RunResult::new(
                    outcome,
                    &result.selection,
                    result.surface.as_ref(),
                    max_steps,
                )),
                Ok(_) => Err(diverged()),
                Err(e) => Err(PlanError::from_implant(e)),
            };
            (run.volume, row)
        })
        .collect();
    let mut body = SweepBody {
        runs: Vec::new(),
        failed_runs: Vec::new(),
    };
    for (volume, row) in &outcomes {
        match row {
            Ok(result) => body.runs.push(SweepRow {
                volume_cm3: *volume,
                result: result.clone(),
            }),
            Err(error) => body.failed_runs.push(FailedRun {
                volume_cm3: *volume,
                error: error.clone(),
            }),
        }
    }
    if body.runs.is_empty() {
        if let Some(first) = body.failed_runs.first() {
            let e = &first.error;
            return Err(PlanError {
                message: format!(
                    "every run of the sweep failed; the first ({} cm³): {}",
                    first.volume_cm3, e.message
                ),
                ..e.clone()
            });
        }
    }
    Ok((Report::new(tool, JobMode::Sweep, inputs, body), outcomes))
}
