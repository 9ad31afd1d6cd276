//! The golden reports (feature `golden`): one job per mode and the report it gives, in
//! `fixtures/reports/` (`NAME.job.json`, `NAME.json`), checked against every front end, so that
//! the same job gives the same report whatever runs it and the contract's fields are only
//! ever added.
//!
//! A front end's test runs each [`JOBS`] entry and calls [`check`] with the report it wrote.
//! Volatile members are masked before the comparison: `wall_time_s` wherever it is, `version`
//! and `tool`. Numbers are compared to a relative 1e-9 (the runs are deterministic; the
//! tolerance only absorbs the last digit of a float printed by another platform's libm).
//! `TISSUE_BLESS=1` rewrites the golden report from the run instead (review the diff).

use std::path::PathBuf;

use serde_json::Value;

/// The golden jobs: `fixtures/reports/NAME.job.json` with their report `NAME.json`.
pub const JOBS: [&str; 4] = ["single", "sweep", "target-gain", "expansion"];

/// `fixtures/reports/`.
pub fn dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/reports")
}

/// The job file of `name` and its JSON text.
///
/// # Errors
/// The file cannot be read.
pub fn job(name: &str) -> Result<(PathBuf, String), String> {
    let path = dir().join(format!("{name}.job.json"));
    let text = std::fs::read_to_string(&path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    Ok((path, text))
}

/// Masks the volatile members of a report.
pub fn mask(report: &mut Value) {
    match report {
        Value::Object(members) => {
            for (key, value) in members.iter_mut() {
                if matches!(key.as_str(), "wall_time_s" | "version" | "tool") {
                    *value = Value::String("(masked)".into());
                } else {
                    mask(value);
                }
            }
        }
        Value::Array(items) => items.iter_mut().for_each(mask),
        _ => {}
    }
}

/// Where `a` and `b` differ (`path: a != b`), after masking, numbers to a relative 1e-9.
pub fn differences(a: &Value, b: &Value) -> Vec<String> {
    let mut out = Vec::new();
    diff("", a, b, &mut out);
    out
}

fn diff(path: &str, a: &Value, b: &Value, out: &mut Vec<String>) {
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let keys_x: Vec<&String> = x.keys().collect();
            let keys_y: Vec<&String> = y.keys().collect();
            if keys_x != keys_y {
                out.push(format!("{path}: members {keys_x:?} != {keys_y:?}"));
                return;
            }
            for (k, v) in x {
                if let Some(w) = y.get(k) {
                    diff(&format!("{path}.{k}"), v, w, out);
                }
            }
        }
        (Value::Array(x), Value::Array(y)) => {
            if x.len() != y.len() {
                out.push(format!("{path}: {} items != {}", x.len(), y.len()));
                return;
            }
            for (i, (v, w)) in x.iter().zip(y).enumerate() {
                diff(&format!("{path}[{i}]"), v, w, out);
            }
        }
        (Value::Number(x), Value::Number(y)) => {
            let (p, q) = (
                x.as_f64().unwrap_or(f64::NAN),
                y.as_f64().unwrap_or(f64::NAN),
            );
            let same_kind = x.is_f64() == y.is_f64();
            if !same_kind || (p - q).abs() > 1e-9 * p.abs().max(q.abs()).max(1e-12) {
                out.push(format!("{path}: {x} != {y}"));
            }
        }
        _ => {
            if a != b {
                out.push(format!("{path}: {a} != {b}"));
            }
        }
    }
}

/// Checks `report` (the JSON text a front end wrote for job `name`) against the golden report.
///
/// # Errors
/// Every difference, one per line, or why the files could not be read; with `TISSUE_BLESS=1`,
/// none (the golden file is rewritten from `report`, its volatile members masked).
pub fn check(name: &str, report: &str) -> Result<(), String> {
    let mut got: Value =
        serde_json::from_str(report).map_err(|e| format!("the report is not JSON: {e}"))?;
    mask(&mut got);
    let path = dir().join(format!("{name}.json"));
    if std::env::var_os("TISSUE_BLESS").is_some_and(|v| v == "1") {
        let text = serde_json::to_string_pretty(&got).map_err(|e| e.to_string())? + "\n";
        return std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()));
    }
    let text = std::fs::read_to_string(&path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let golden: Value =
        serde_json::from_str(&text).map_err(|e| format!("{} is not JSON: {e}", path.display()))?;
    let differences = differences(&golden, &got);
    if differences.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "the {name} report differs from {} (golden != got; TISSUE_BLESS=1 rewrites it if \
             the change is meant):\n{}",
            path.display(),
            differences.join("\n")
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn masking_and_differences() -> Result<(), serde_json::Error> {
        let mut a: Value = serde_json::from_str(
            r#"{"tool": "insert", "runs": [{"wall_time_s": 1.5, "x": 1.0}], "n": 3}"#,
        )?;
        let mut b: Value = serde_json::from_str(
            r#"{"tool": "studio", "runs": [{"wall_time_s": 9.0, "x": 1.0000000000001}], "n": 3}"#,
        )?;
        mask(&mut a);
        mask(&mut b);
        assert!(differences(&a, &b).is_empty());
        let c: Value = serde_json::from_str(
            r#"{"tool": "(masked)", "runs": [{"wall_time_s": "(masked)", "x": 1.1}], "n": 3}"#,
        )?;
        assert_eq!(differences(&a, &c), [".runs[0].x: 1.0 != 1.1"]);
        let d: Value = serde_json::from_str(r#"{"tool": "(masked)", "n": 3}"#)?;
        assert_eq!(differences(&a, &d).len(), 1, "a member less");
        Ok(())
    }
}
