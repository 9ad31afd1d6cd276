//! The studio's JSON messages, typed: what the job socket sends and receives, and the error body
//! of every answer. The server builds them and its tests read them with the same types.

use serde::{Deserialize, Serialize};
use serde_json::Value;
use tissue_planner::{
    DomePreview, ErrorKind as PlanKind, JobMode, JobSpec, PlanError, PlanRequest,
};

/// What went wrong, as the page and a script see it (`error.kind`): the planner's kinds and the
/// server's own.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorKind {
    /// The request or message is incomplete or unknown.
    Usage,
    /// The patient file is missing, unreadable or of an unsupported type.
    Input,
    /// The patient file is malformed or its surface invalid.
    Mesh,
    /// The point is off the surface or the region does not fit.
    Placement,
    /// A parameter is out of range.
    Parameters,
    /// The run diverged or failed.
    Run,
    /// An output could not be written.
    Output,
    /// The job was cancelled.
    Cancelled,
    /// A job runs already (one at a time), or every slot of its kind is taken.
    Busy,
    /// An upload or message over its limit.
    TooLarge,
    /// No such patient, job, result or page.
    NotFound,
    /// The client was too slow.
    Timeout,
    /// Another site's page, or a host name not served.
    Forbidden,
    /// A token is needed.
    Unauthorized,
    /// The case library failed (its database, damaged stored data, a full disk).
    Library,
}

impl From<PlanKind> for ErrorKind {
    fn from(kind: PlanKind) -> Self {
        match kind {
            PlanKind::Usage => ErrorKind::Usage,
            PlanKind::Input => ErrorKind::Input,
            PlanKind::Mesh => ErrorKind::Mesh,
            PlanKind::Placement => ErrorKind::Placement,
            PlanKind::Parameters => ErrorKind::Parameters,
            PlanKind::Run => ErrorKind::Run,
            PlanKind::Output => ErrorKind::Output,
            PlanKind::Cancelled => ErrorKind::Cancelled,
        }
    }
}

/// The JSON of an error: `{kind, field, message}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ErrorBody {
    /// What kind of failure.
    pub kind: ErrorKind,
    /// The request field at fault (its JSON name), if one is: the page marks its input.
    pub field: Option<String>,
    /// One sentence for the user, request fields named as the page labels them.
    pub message: String,
}

impl ErrorBody {
    /// An error of `kind` about no field in particular.
    pub fn new(kind: ErrorKind, message: impl Into<String>) -> Self {
        ErrorBody {
            kind,
            field: None,
            message: message.into(),
        }
    }

    /// The planner's error as the page shows it (request fields named as the page labels them).
    pub fn of(e: &PlanError) -> ErrorBody {
        ErrorBody {
            kind: e.kind.into(),
            field: e.field.map(str::to_owned),
            message: e.message_with(label_of),
        }
    }
}

/// How the page labels a request or job field (`None` for a name that is not one).
pub fn label_of(field: &str) -> Option<&'static str> {
    Some(match field {
        "at" | "vertex" => "placement",
        "tangent" | "rotation_deg" => "rotation",
        "shape" => "shape",
        "diameter_cm" => "diameter",
        "length_cm" => "length",
        "width_cm" => "width",
        "corner_radius_cm" => "corner radius",
        "bend_radius_cm" => "bend radius",
        "volume_cm3" => "volume",
        "implant_vertices" => "implant vertices",
        "volumes_cm3" => "volumes for a series",
        "depth_cm" => "depth under the skin",
        "region_radius_cm" => "region radius",
        "region_rule" => "region rule",
        "sim_edge_cm" => "simulation edge",
        "scan_triangles" => "the scan's own triangles",
        "max_hole_cm" => "largest hole filled",
        "young_kpa" => "skin Young's modulus",
        "poisson" => "skin Poisson ratio",
        "thickness_cm" => "skin thickness",
        "density_g_cm3" => "tissue density",
        "detect" => "contact detection",
        "solver" => "solver",
        "max_steps" => "step limit",
        "time_step_s" => "time step",
        "target_gain_cm2" => "target skin gain",
        "bracket_cm3" => "volume bracket for the search",
        "gain_tolerance_cm2" => "gain tolerance",
        "expand_weeks" => "expansion over weeks",
        "hold_weeks" => "weeks of hold",
        "leakage" => "leakage",
        "overfill" => "over-fill",
        "band_samples" => "band samples",
        "band_seed" => "band seed",
        "growth_step_h" => "growth step",
        "mode" => "mode",
        "unit" => "unit",
        "mesh" => "file",
        _ => return None,
    })
}

/// A message from the page on the job socket.
#[derive(Debug, Deserialize, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ClientMessage {
    /// Run a job.
    Run(Box<RunMessage>),
    /// Cancel this tab's job.
    Cancel,
    /// Preview the dome of a request, coarse and quick (tissue-planner's [`tissue_planner::Previewer`]);
    /// it replaces the tab's preview in progress, which is cancelled.
    Preview(Box<PreviewMessage>),
}

/// A live preview: the patient, the page's sequence number (echoed in the answer, so that the
/// page draws only the newest) and the planning request, as a run would send it.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PreviewMessage {
    /// The id an upload or a shipped patient returned.
    pub patient: String,
    /// The page's number for this preview (any; the page counts up).
    #[serde(default)]
    pub seq: u64,
    /// What to plan; made coarse by the planner.
    #[serde(default)]
    pub request: PlanRequest,
}

/// A run: the patient's id and what to run, tissue-planner's [`JobSpec`] (the C ABI's job
/// JSON) beside it, whose unknown members are refused (serde's `flatten` would let them
/// through).
#[derive(Debug)]
pub struct RunMessage {
    /// The id an upload or a shipped patient returned.
    pub patient: String,
    /// What to run.
    pub spec: JobSpec,
}

impl<'de> Deserialize<'de> for RunMessage {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let mut members = serde_json::Map::<String, Value>::deserialize(d)?;
        let Some(Value::String(patient)) = members.remove("patient") else {
            return Err(D::Error::custom(
                "a run needs `patient`: the id an upload or a shipped patient returned",
            ));
        };
        let spec = JobSpec::deserialize(Value::Object(members)).map_err(D::Error::custom)?;
        Ok(RunMessage { patient, spec })
    }
}

impl Serialize for RunMessage {
    /// `{patient, mode, request, …}`: the job's members beside the patient.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::{Error, SerializeMap};
        let spec = serde_json::to_value(&self.spec).map_err(S::Error::custom)?;
        let Value::Object(members) = spec else {
            return Err(S::Error::custom("a job spec is an object"));
        };
        let mut map = s.serialize_map(Some(members.len() + 1))?;
        map.serialize_entry("patient", &self.patient)?;
        for (k, v) in &members {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }
}

/// A single run's per-vertex fields for the page: every vertex after (cm, flat xyz), its
/// displacement (the file's unit), stretch (1 outside the region) and in-region flag.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Fields {
    /// Positions after, cm, `[x0, y0, z0, x1, …]`.
    pub after: Vec<f32>,
    /// How far each vertex moved, the file's unit.
    pub displacement: Vec<f32>,
    /// Area after / before around each vertex; 1 outside the region.
    pub stretch: Vec<f32>,
    /// 1 in the region, 0 outside.
    pub in_region: Vec<f32>,
}

impl Fields {
    /// The fields of a single run's result on the patient (`scale` cm per file unit): what the
    /// job's `finished` message and an opened plan (`GET /api/cases/plans/{uid}`) both send.
    pub fn of(patient: &tissue_planner::PatientResult, scale: f32) -> Fields {
        Fields {
            after: patient
                .after_cm
                .positions()
                .iter()
                .flat_map(|p| p.to_array())
                .collect(),
            displacement: patient.displacement.iter().map(|d| d * scale).collect(),
            stretch: patient.stretch_or_one(),
            in_region: patient.in_region.clone(),
        }
    }
}

/// A failed run of a sweep, as the page shows it.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FailedRow {
    /// The run's volume, cm³.
    pub volume_cm3: f64,
    /// Why it has no results.
    pub error: ErrorBody,
}

/// A message from the server on the job socket: `accepted`, then `progress` (at most every
/// 50 ms), then one terminal message (`finished`, `cancelled` or `failed`); `refused` answers a
/// run that was not started.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum JobMessage {
    /// The run was accepted as `job`.
    Accepted {
        /// The job's id.
        job: String,
        /// What runs.
        mode: JobMode,
    },
    /// A step of one of the job's runs.
    Progress {
        /// The job's id.
        job: String,
        /// The run (0 for a single run).
        run: usize,
        /// The runs known so far.
        runs: usize,
        /// Steps of this run (of this settle, in an expansion).
        step: u64,
        /// Its step limit.
        max_steps: u64,
        /// How close the stop criterion is, 0 to 1.
        settle: f64,
        /// Seconds since the job started.
        elapsed_s: f64,
        /// An expansion's protocol day.
        day: Option<f64>,
    },
    /// The job finished: its report (the planner's JSON) and, for a single run, the fields.
    Finished {
        /// The job's id.
        job: String,
        /// The report, as `report.json`.
        report: Value,
        /// A single run's per-vertex fields (null for the other modes).
        fields: Option<Box<Fields>>,
        /// A sweep's failed runs (the report's `failed_runs`), their messages labelled for the
        /// page; absent when none failed.
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        failed_runs: Vec<FailedRow>,
    },
    /// The job was cancelled after `steps` steps.
    Cancelled {
        /// The job's id.
        job: String,
        /// Steps done.
        steps: u64,
    },
    /// The job failed.
    Failed {
        /// The job's id.
        job: String,
        /// Why.
        error: ErrorBody,
    },
    /// The run was not started.
    Refused {
        /// Why.
        error: ErrorBody,
    },
    /// A live preview's answer: the dome and its gain, or why the request cannot run. Only the
    /// newest preview of a tab is answered: one replaced while it ran is dropped.
    Preview {
        /// The page's `seq` of the preview message.
        seq: u64,
        /// Previews this socket has run to their end so far (replaced ones and repeats of the
        /// last are not counted).
        computed: u64,
        /// The preview, when it ran.
        preview: Option<Box<DomePreview>>,
        /// Why not (the request field at fault named as in a run's error).
        error: Option<ErrorBody>,
    },
}

impl JobMessage {
    /// The progress of `job` (of `runs` runs known ahead) at `p`.
    pub fn progress(job: &str, runs: usize, p: &tissue_planner::ProgressEvent) -> Self {
        JobMessage::Progress {
            job: job.to_owned(),
            run: p.run,
            runs: runs.max(p.run + 1),
            step: p.step,
            max_steps: p.max_steps,
            settle: p.settle,
            elapsed_s: p.elapsed.as_secs_f64(),
            day: p.day,
        }
    }

    /// The job a terminal message ends (`finished`, `cancelled`, `failed`), if it is one.
    pub fn ended_job(&self) -> Option<&str> {
        match self {
            JobMessage::Finished { job, .. }
            | JobMessage::Cancelled { job, .. }
            | JobMessage::Failed { job, .. } => Some(job),
            JobMessage::Accepted { .. }
            | JobMessage::Progress { .. }
            | JobMessage::Refused { .. }
            | JobMessage::Preview { .. } => None,
        }
    }
}

#[cfg(test)]
#[allow(clippy::panic)]
mod tests {
    use super::*;

    /// Every field a request or a job can name has a label, so no message shows a raw JSON
    /// name.
    #[test]
    fn every_request_and_job_field_has_a_label() -> Result<(), serde_json::Error> {
        let request = serde_json::to_value(tissue_planner::PlanRequest::default())?;
        let job = serde_json::to_value(JobSpec::default())?;
        let keys = request
            .as_object()
            .into_iter()
            .chain(job.as_object())
            .flat_map(|o| o.keys())
            .filter(|k| *k != "request");
        for field in keys {
            assert!(label_of(field).is_some(), "no label for {field}");
        }
        Ok(())
    }

    #[test]
    fn a_run_message_round_trips_and_unknown_members_are_refused() -> Result<(), serde_json::Error>
    {
        let text = r#"{"type": "run", "patient": "p1", "mode": "sweep", "volumes_cm3": [50]}"#;
        let ClientMessage::Run(run) = serde_json::from_str(text)? else {
            panic!("not a run");
        };
        assert_eq!(run.patient, "p1");
        assert_eq!(run.spec.mode, JobMode::Sweep);
        let again: ClientMessage =
            serde_json::from_value(serde_json::to_value(ClientMessage::Run(run))?)?;
        assert!(matches!(again, ClientMessage::Run(r) if r.spec.volumes_cm3 == [50.0]));
        let unknown = r#"{"type": "run", "patient": "p1", "volume": 50}"#;
        assert!(serde_json::from_str::<ClientMessage>(unknown).is_err());
        Ok(())
    }

    #[test]
    fn a_preview_message_round_trips_and_unknown_members_are_refused(
    ) -> Result<(), serde_json::Error> {
        let text =
            r#"{"type": "preview", "patient": "p1", "seq": 7, "request": {"volume_cm3": 90}}"#;
        let ClientMessage::Preview(p) = serde_json::from_str(text)? else {
            panic!("not a preview");
        };
        assert_eq!(
            (p.patient.as_str(), p.seq, p.request.volume_cm3),
            ("p1", 7, 90.0)
        );
        let again: ClientMessage =
            serde_json::from_value(serde_json::to_value(ClientMessage::Preview(p))?)?;
        assert!(matches!(again, ClientMessage::Preview(p) if p.seq == 7));
        for unknown in [
            r#"{"type": "preview", "patient": "p1", "volume": 50}"#,
            r#"{"type": "preview", "patient": "p1", "request": {"volume": 50}}"#,
            r#"{"type": "preview", "seq": 1}"#,
        ] {
            assert!(
                serde_json::from_str::<ClientMessage>(unknown).is_err(),
                "{unknown}"
            );
        }
        Ok(())
    }
}
