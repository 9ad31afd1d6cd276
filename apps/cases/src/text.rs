//! What the commands print: the readable tables and the JSON shapes (`--json`).

use serde::Serialize;
use tissue_cases::{ImportSummary, PatientInfo, PlanInfo, StoredPlan};

/// A patient with its plans: one entry of `list --json`, and `show p… --json`.
#[derive(Debug, Serialize)]
pub struct PatientEntry {
    /// The patient.
    pub patient: PatientInfo,
    /// Its plans, newest first.
    pub plans: Vec<PlanInfo>,
}

/// `show c… --json`: the plan, its patient, its job and its report (as JSON values).
#[derive(Debug, Serialize)]
pub struct PlanEntry<'a> {
    /// The plan.
    pub plan: &'a PlanInfo,
    /// Its patient.
    pub patient: &'a PatientInfo,
    /// The job as it was asked.
    pub job: serde_json::Value,
    /// The report.
    pub report: serde_json::Value,
}

impl<'a> PlanEntry<'a> {
    /// `plan`'s entry; a stored text that is not JSON is kept as a string.
    pub fn of(plan: &'a StoredPlan) -> Self {
        let value = |text: &str| {
            serde_json::from_str(text).unwrap_or_else(|_| serde_json::Value::String(text.into()))
        };
        PlanEntry {
            plan: &plan.info,
            patient: &plan.patient,
            job: value(&plan.job_json),
            report: value(&plan.report_json),
        }
    }
}

/// Pretty JSON with a final line break.
pub fn json<T: Serialize>(value: &T) -> String {
    let mut s = serde_json::to_string_pretty(value).unwrap_or_else(|e| format!("\"{e}\""));
    s.push('\n');
    s
}

/// A figure with its unit, or `-`.
fn figure(value: Option<f64>, unit: &str) -> String {
    match value {
        Some(v) => format!("{v:.2} {unit}"),
        None => "-".to_owned(),
    }
}

/// "1 plan", "3 plans".
fn plans_word(n: u64) -> String {
    match n {
        1 => "1 plan".to_owned(),
        n => format!("{n} plans"),
    }
}

/// A patient's heading line in a list.
fn patient_line(p: &PatientInfo) -> String {
    format!(
        "{}  {:?}  {}, {} ({} bytes), {}, added {}\n",
        p.uid,
        p.label,
        p.scan_name,
        p.unit,
        p.scan_bytes,
        plans_word(p.plans),
        p.added_at
    )
}

/// Plans as rows: id, name, mode, when run, area gain, volume.
fn plan_rows(plans: &[PlanInfo], indent: &str) -> String {
    let name_w = plans
        .iter()
        .map(|p| p.name.chars().count())
        .max()
        .unwrap_or(0)
        .max(4);
    let mode_w = plans.iter().map(|p| p.mode.len()).max().unwrap_or(0).max(4);
    let mut s = String::new();
    for p in plans {
        let pad = name_w - p.name.chars().count();
        s.push_str(&format!(
            "{indent}{}  {}{}  {:<mode_w$}  {}  gain {:>11}  volume {:>11}\n",
            p.uid,
            p.name,
            " ".repeat(pad),
            p.mode,
            p.run_at,
            figure(p.area_gain_cm2, "cm²"),
            figure(p.volume_cm3, "cm³"),
        ));
    }
    s
}

/// `list`: each patient, then its plans indented.
pub fn list(entries: &[PatientEntry]) -> String {
    let mut s = String::new();
    for (i, e) in entries.iter().enumerate() {
        if i > 0 {
            s.push('\n');
        }
        s.push_str(&patient_line(&e.patient));
        s.push_str(&plan_rows(&e.plans, "  "));
    }
    s
}

/// `show p…`: the patient's details and its plans.
pub fn patient(e: &PatientEntry) -> String {
    let p = &e.patient;
    let mut s = format!("patient {}\n", p.uid);
    s.push_str(&format!("  label        {}\n", p.label));
    s.push_str(&format!(
        "  scan         {} ({}, {} bytes)\n",
        p.scan_name, p.unit, p.scan_bytes
    ));
    s.push_str(&format!("  sha-256      {}\n", p.scan_sha256));
    let count = |k: &str| p.summary.get(k).and_then(serde_json::Value::as_u64);
    if let (Some(v), Some(t)) = (count("vertices"), count("triangles")) {
        s.push_str(&format!("  surface      {v} vertices, {t} triangles\n"));
    }
    s.push_str(&format!("  added        {}\n", p.added_at));
    s.push_str(&format!("{}:\n", plans_word(p.plans)));
    s.push_str(&plan_rows(&e.plans, "  "));
    s
}

/// `show c…`: the plan's details, then its report.
pub fn plan(plan: &StoredPlan) -> String {
    let i = &plan.info;
    let mut s = format!("plan {}\n", i.uid);
    s.push_str(&format!("  name         {}\n", i.name));
    if !i.note.is_empty() {
        // A note of several lines: each under the first.
        let note = i.note.lines().collect::<Vec<_>>().join("\n               ");
        s.push_str(&format!("  note         {note}\n"));
    }
    s.push_str(&format!(
        "  patient      {} {:?}\n",
        plan.patient.uid, plan.patient.label
    ));
    s.push_str(&format!("  mode         {}\n", i.mode));
    s.push_str(&format!("  solver       {}\n", i.solver));
    s.push_str(&format!(
        "  run          {} by {} {}\n",
        i.run_at, i.tool, i.library_version
    ));
    s.push_str(&format!(
        "  area gain    {}\n",
        figure(i.area_gain_cm2, "cm²")
    ));
    s.push_str(&format!("  volume       {}\n", figure(i.volume_cm3, "cm³")));
    s.push_str(&format!(
        "  result       {}\n",
        if i.has_result {
            "the patient after, with its fields"
        } else {
            "none (not a single run)"
        }
    ));
    s.push_str("report:\n");
    s.push_str(&plan.report_json);
    if !plan.report_json.ends_with('\n') {
        s.push('\n');
    }
    s
}

/// `import`: what was added.
pub fn import(summary: &ImportSummary) -> String {
    format!(
        "imported patient {} {:?}: {} added, {} already in the library\n",
        summary.patient.uid,
        summary.patient.label,
        plans_word(summary.plans_added),
        summary.plans_skipped
    )
}
