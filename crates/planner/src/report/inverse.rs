//! `mode: "target-gain"`: the volume that gains a wanted area of skin, and every run of the
//! search.

use serde::Serialize;
use tissue_app::PlannedInverse;

use super::{Inputs, Report, Tool};
use crate::job::JobMode;

/// `mode: "target-gain"`: the envelope and the search's answer.
pub type InverseReport = Report<InverseBody>;

/// One run of a search.
#[derive(Debug, Clone, Serialize)]
pub struct SearchRun {
    /// The implant volume run, cm³.
    pub volume_cm3: f64,
    /// The area gain it gave, cm².
    pub area_gain_cm2: f64,
    /// The solver's iterations: the explicit solver's steps, or the quasi-static solver's
    /// iterations.
    pub iterations: u64,
    /// The quasi-static solver's final residual, N; null for the explicit solver.
    pub residual_n: Option<f64>,
}

/// The search's answer.
#[derive(Debug, Clone, Serialize)]
pub struct InverseBody {
    /// The wanted area gain, cm².
    pub target_gain_cm2: f64,
    /// The volumes searched between, cm³.
    pub bracket_cm3: [f64; 2],
    /// The answer, cm³.
    pub volume_cm3: f64,
    /// The area gain of the answer's run, cm².
    pub area_gain_cm2: f64,
    /// Whether a stopping rule was met (else the run budget ran out: best estimate).
    pub converged: bool,
    /// Every run, in order.
    pub runs: Vec<SearchRun>,
}

/// The search report.
pub(crate) fn inverse(
    tool: Tool,
    mut inputs: Inputs,
    target: f64,
    bracket: (f64, f64),
    planned: &PlannedInverse,
) -> InverseReport {
    let search = &planned.search;
    inputs.target_gain_cm2 = Some(target);
    inputs.bracket_cm3 = Some([bracket.0, bracket.1]);
    let body = InverseBody {
        target_gain_cm2: target,
        bracket_cm3: [bracket.0, bracket.1],
        volume_cm3: search.volume,
        area_gain_cm2: search.gain,
        converged: search.converged,
        // One figure per run, in order (tissue-app's `PlannedInverse`).
        runs: search
            .runs
            .iter()
            .zip(&planned.runs)
            .map(|(r, f)| SearchRun {
                volume_cm3: r.volume,
                area_gain_cm2: r.gain,
                iterations: f.iterations,
                residual_n: f.residual_n,
            })
            .collect(),
    };
    Report::new(tool, JobMode::TargetGain, inputs, body)
}
