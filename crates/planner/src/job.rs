//! What a front end asks to run, in one JSON shape: the studio's run message and the C ABI's
//! `tissue_job_start_json` both take a [`JobSpec`], so a mode one of them knows the other knows
//! too.

use serde::{Deserialize, Serialize};

use crate::{ErrorKind, PlanError, PlanRequest, Scenario};

/// What to run on a placed request (the report's `mode`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum JobMode {
    /// One insertion (the default).
    #[default]
    Single,
    /// The insertion at each of [`JobSpec::volumes_cm3`].
    Sweep,
    /// The volume that gains [`JobSpec::target_gain_cm2`] of skin.
    TargetGain,
    /// Expansion over weeks: the request's `expand_weeks` and its companions. `expand_weeks`
    /// asks for this mode and for no other: any other mode with it is refused, naming the field.
    Expansion,
}

impl JobMode {
    /// Its JSON name.
    pub fn name(self) -> &'static str {
        match self {
            JobMode::Single => "single",
            JobMode::Sweep => "sweep",
            JobMode::TargetGain => "target-gain",
            JobMode::Expansion => "expansion",
        }
    }
}

/// A job as JSON: `{"mode": "single" | "sweep" | "target-gain" | "expansion", "request": {…},
/// "volumes_cm3": [..], "target_gain_cm2": 30, "bracket_cm3": [lo, hi], "gain_tolerance_cm2":
/// 0.5}`; every member optional (`{}` is Table 2's single run), unknown members refused.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JobSpec {
    /// What to run.
    #[serde(default)]
    pub mode: JobMode,
    /// The planner's request.
    #[serde(default)]
    pub request: PlanRequest,
    /// A sweep's volumes (cm³).
    #[serde(default)]
    pub volumes_cm3: Vec<f64>,
    /// The search's target (cm²).
    pub target_gain_cm2: Option<f64>,
    /// The search's bracket (cm³); default a quarter to twice the request's volume.
    pub bracket_cm3: Option<(f64, f64)>,
    /// The search's tolerance (cm²); default [`crate::default_gain_tolerance`].
    pub gain_tolerance_cm2: Option<f64>,
}

/// A job ready for [`tissue_app`]'s worker, with what its report needs afterwards.
#[derive(Debug)]
pub struct PlannedJob {
    /// The worker's job.
    pub job: tissue_app::Job,
    /// Runs it makes, for progress (0 when not known ahead: the search).
    pub runs: usize,
    /// Its kind, with the figures the report repeats.
    pub kind: JobKind,
}

/// A planned job's kind.
#[derive(Debug, Clone)]
pub enum JobKind {
    /// One insertion.
    Single,
    /// A sweep.
    Sweep,
    /// The search: its target (cm²) and the bracket it searched (cm³).
    TargetGain {
        /// cm².
        target: f64,
        /// cm³.
        bracket: (f64, f64),
    },
    /// Expansion over weeks, with its job (the report restates its protocol).
    Expansion(Box<tissue_app::ExpansionJob>),
}

impl JobSpec {
    /// Checks what can be checked before the patient is read: the request
    /// ([`PlanRequest::check`]), that its members belong to its mode, a sweep's volumes and a
    /// search's target, bracket and tolerance.
    ///
    /// # Errors
    /// A [`PlanError`] naming the member at fault: `expand_weeks` outside an expansion (it
    /// asks for one), an expansion without it, a search without `target_gain_cm2`, and the
    /// checks of [`crate::check_sweep`] and [`crate::check_search`].
    pub fn check(&self) -> Result<(), PlanError> {
        self.request.check()?;
        let expansion = self.mode == JobMode::Expansion;
        match (expansion, self.request.expand_weeks) {
            (false, Some(_)) => {
                return Err(PlanError::field(
                    ErrorKind::Usage,
                    "expand_weeks",
                    format!(
                        "`expand_weeks` asks for an expansion over weeks, not a {} run: run the \
                         job as an expansion (mode `expansion`), or leave `expand_weeks` out",
                        self.mode.name()
                    ),
                ))
            }
            (true, None) => {
                return Err(PlanError::field(
                    ErrorKind::Usage,
                    "expand_weeks",
                    "an expansion needs `expand_weeks` in the request",
                ))
            }
            _ => {}
        }
        match self.mode {
            JobMode::Sweep => crate::check_sweep(&self.volumes_cm3)?,
            JobMode::TargetGain => {
                crate::check_search(
                    self.target()?,
                    self.bracket_cm3,
                    self.tolerance(),
                    self.request.volume_cm3,
                )?;
            }
            JobMode::Single | JobMode::Expansion => {}
        }
        Ok(())
    }

    fn target(&self) -> Result<f64, PlanError> {
        self.target_gain_cm2.ok_or_else(|| {
            PlanError::field(
                ErrorKind::Usage,
                "target_gain_cm2",
                "a search needs `target_gain_cm2`",
            )
        })
    }

    fn tolerance(&self) -> f64 {
        self.gain_tolerance_cm2
            .unwrap_or_else(crate::default_gain_tolerance)
    }

    /// The job on `scenario` (placed from [`JobSpec::request`]); run it with
    /// [`PlannedJob::run`].
    ///
    /// # Errors
    /// [`JobSpec::check`]'s, and those of [`Scenario::sweep_job`],
    /// [`Scenario::inverse_job`] and [`Scenario::expansion_job`].
    pub fn plan(&self, scenario: &Scenario) -> Result<PlannedJob, PlanError> {
        use tissue_app::Job;
        self.check()?;
        Ok(match self.mode {
            JobMode::Single => PlannedJob {
                job: Job::Insertion(scenario.job.clone()),
                runs: 1,
                kind: JobKind::Single,
            },
            JobMode::Sweep => PlannedJob {
                job: Job::Sweep(scenario.sweep_job(&self.volumes_cm3)?),
                runs: self.volumes_cm3.len(),
                kind: JobKind::Sweep,
            },
            JobMode::TargetGain => {
                let target = self.target()?;
                let job = scenario.inverse_job(target, self.bracket_cm3, self.tolerance())?;
                let bracket = job.bracket;
                PlannedJob {
                    job: Job::Inverse(job),
                    runs: 0,
                    kind: JobKind::TargetGain { target, bracket },
                }
            }
            JobMode::Expansion => {
                let job = scenario.expansion_job()?.ok_or_else(|| {
                    PlanError::field(
                        ErrorKind::Usage,
                        "expand_weeks",
                        "an expansion needs `expand_weeks` in the request",
                    )
                })?;
                PlannedJob {
                    job: Job::Expansion(Box::new(job.clone())),
                    runs: 1,
                    kind: JobKind::Expansion(Box::new(job)),
                }
            }
        })
    }
}

#[cfg(test)]
#[allow(clippy::panic)]
mod tests {
    use super::*;
    use crate::{Patient, Shipped};

    fn planned(json: &str) -> Result<PlannedJob, PlanError> {
        let spec: JobSpec = serde_json::from_str(json)
            .map_err(|e| PlanError::new(ErrorKind::Usage, e.to_string()))?;
        let scenario = Scenario::new(Patient::shipped(Shipped::Table2)?, spec.request.clone())?;
        spec.plan(&scenario)
    }

    #[test]
    fn every_mode_plans_its_job_and_a_missing_member_is_named() -> Result<(), PlanError> {
        let single = planned("{}")?;
        assert!(matches!(
            (single.job, single.kind),
            (tissue_app::Job::Insertion(_), JobKind::Single)
        ));
        let sweep = planned(r#"{"mode": "sweep", "volumes_cm3": [50, 100, 150]}"#)?;
        assert_eq!(sweep.runs, 3);
        match sweep.job {
            tissue_app::Job::Sweep(job) => assert_eq!(job.volumes, [50.0, 100.0, 150.0]),
            other => panic!("a sweep planned as {other:?}"),
        }
        let search = planned(r#"{"mode": "target-gain", "target_gain_cm2": 30}"#)?;
        match search.kind {
            // The default bracket: a quarter to twice Table 2's 100 cm³.
            JobKind::TargetGain { target, bracket } => {
                assert_eq!(target, 30.0);
                assert_eq!(bracket, (25.0, 200.0));
            }
            other => panic!("a search planned as {other:?}"),
        }
        let weeks = planned(r#"{"mode": "expansion", "request": {"expand_weeks": 3}}"#)?;
        match weeks.kind {
            JobKind::Expansion(job) => assert_eq!(job.protocol.fills.len(), 3),
            other => panic!("an expansion planned as {other:?}"),
        }
        let missing = planned(r#"{"mode": "target-gain"}"#).err();
        assert_eq!(missing.and_then(|e| e.field), Some("target_gain_cm2"));
        let missing = planned(r#"{"mode": "expansion"}"#).err();
        assert_eq!(missing.and_then(|e| e.field), Some("expand_weeks"));
        // `expand_weeks` asks for an expansion: in any other mode it is refused, by name, the
        // same in every front end (it was silently a single run in two of them).
        for mode in ["single", "sweep", "target-gain"] {
            let json = format!(
                r#"{{"mode": "{mode}", "request": {{"expand_weeks": 3}}, "volumes_cm3": [50],
                    "target_gain_cm2": 30}}"#
            );
            let refused = planned(&json).err();
            assert_eq!(
                refused.map(|e| (e.kind, e.field)),
                Some((ErrorKind::Usage, Some("expand_weeks"))),
                "{mode}"
            );
        }
        let empty = planned(r#"{"mode": "sweep"}"#).err();
        assert!(empty.is_some(), "a sweep of no volume");
        let volumes = vec!["50"; crate::MAX_SWEEP_VOLUMES + 1].join(", ");
        let many = planned(&format!(
            r#"{{"mode": "sweep", "volumes_cm3": [{volumes}]}}"#
        ))
        .err();
        assert_eq!(
            many.map(|e| (e.kind, e.field)),
            Some((ErrorKind::Parameters, Some("volumes_cm3")))
        );
        let steps = planned(r#"{"request": {"max_steps": 1000000000000}}"#).err();
        assert_eq!(steps.and_then(|e| e.field), Some("max_steps"));
        assert!(
            planned(r#"{"mode": "single", "volume": 50}"#).is_err(),
            "unknown member"
        );
        Ok(())
    }
}
