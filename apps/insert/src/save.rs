//! `--save NAME`: the run stored as a plan in the case library (tissue-cases), for the patient
//! of its scan. The name, note and label are checked and the library opened before anything
//! runs, so that a typo or an unusable `--data` costs no run; the plan is saved after the
//! outputs were written, in one transaction of the library (Ctrl-C only sets a flag, so the
//! process never ends in the middle of it).

use std::path::PathBuf;

use tissue_cases::{CaseError, Library, NewPlan, PlanInfo, Scan, MAX_NAME_CHARS, MAX_NOTE_CHARS};
use tissue_planner::{Finished, JobSpec, Scenario};

use crate::cli::Cli;
use crate::failure::{Exit, Failure};

/// The patient label of the generated Table 2 plane.
pub const TABLE2_LABEL: &str = "Table 2 plane";

/// The scan's name in the library when the patient is the generated Table 2 plane.
const TABLE2_SCAN: &str = "table2";

/// A run to be saved: the library, open, and what the plan is called.
#[derive(Debug)]
pub struct Saving {
    library: Library,
    name: String,
    note: String,
    label: Option<String>,
}

/// Refuses a name or label the library would refuse: empty after trimming, longer than
/// [`MAX_NAME_CHARS`], or with a control character (a line break, a tab). The library's own
/// check is not public, so its rule is repeated here to refuse before the run; its limits are
/// the library's constants.
fn check_name(flag: &str, value: &str) -> Result<(), Failure> {
    let trimmed = value.trim();
    let problem = if trimmed.is_empty() {
        Some("is empty; give a name, e.g. --save \"first plan\"".to_owned())
    } else if trimmed.chars().count() > MAX_NAME_CHARS {
        Some(format!(
            "has {} characters; give at most {MAX_NAME_CHARS}",
            trimmed.chars().count()
        ))
    } else if trimmed.chars().any(char::is_control) {
        Some("has a control character (a line break, a tab); give one line of text".to_owned())
    } else {
        None
    };
    match problem {
        Some(p) => Err(Failure::new(Exit::Usage, format!("{flag} {value:?} {p}"))),
        None => Ok(()),
    }
}

/// Refuses a note the library would refuse: longer than [`MAX_NOTE_CHARS`], or with a control
/// character other than a line break or a tab.
fn check_note(note: &str) -> Result<(), Failure> {
    let n = note.chars().count();
    if n > MAX_NOTE_CHARS {
        return Err(Failure::new(
            Exit::Usage,
            format!("--note has {n} characters; give at most {MAX_NOTE_CHARS}"),
        ));
    }
    if let Some(c) = note
        .chars()
        .find(|&c| c.is_control() && !matches!(c, '\n' | '\r' | '\t'))
    {
        return Err(Failure::new(
            Exit::Usage,
            format!("--note holds a control character ({c:?}); use text, line breaks and tabs"),
        ));
    }
    Ok(())
}

/// The library's folder: `--data` or the platform's data folder.
pub fn data_dir(data: Option<&PathBuf>) -> Result<PathBuf, Failure> {
    match data {
        Some(dir) => Ok(dir.clone()),
        None => {
            tissue_cases::default_data_dir().map_err(|e| Failure::new(Exit::Usage, e.to_string()))
        }
    }
}

/// The library's errors as `insert` reports them: a bad name is a usage error, anything else
/// means the plan could not be stored (the output code).
fn library_failure(e: &CaseError, context: &str) -> Failure {
    let code = match e {
        CaseError::Invalid { .. } | CaseError::NoDataDir => Exit::Usage,
        _ => Exit::Output,
    };
    Failure::new(code, format!("{context}{e}"))
}

impl Saving {
    /// With `--save`: the name, note and label checked and the library opened (made when new),
    /// before the run. Without it: nothing, and the library is not touched.
    ///
    /// # Errors
    /// A name, note or label the library would refuse (usage); a library that cannot be opened
    /// (output).
    pub fn prepare(cli: &Cli) -> Result<Option<Saving>, Failure> {
        let Some(name) = &cli.save else {
            return Ok(None);
        };
        check_name("--save", name)?;
        if let Some(label) = &cli.label {
            check_name("--label", label)?;
        }
        let note = cli.note.clone().unwrap_or_default();
        check_note(&note)?;
        let dir = data_dir(cli.data.as_ref())?;
        let library = Library::open(&dir).map_err(|e| library_failure(&e, "--save: "))?;
        let label = match (&cli.label, &cli.mesh) {
            (Some(label), _) => Some(label.clone()),
            (None, Some(_)) => None,
            (None, None) => Some(TABLE2_LABEL.to_owned()),
        };
        Ok(Some(Saving {
            library,
            name: name.clone(),
            note,
            label,
        }))
    }

    /// The scan the run plans on, as the library stores it: the `--mesh` file's bytes in its
    /// unit, or the generated Table 2 plane written as OBJ.
    ///
    /// # Errors
    /// The file cannot be read again (input).
    pub fn scan(cli: &Cli, scenario: &Scenario) -> Result<Scan, Failure> {
        match &cli.mesh {
            Some(path) => Scan::read(path, cli.unit()).map_err(|e| {
                Failure::new(
                    Exit::Input,
                    format!("--save: cannot read the scan again: {e}"),
                )
            }),
            None => Scan::of_mesh(&scenario.patient, TABLE2_SCAN)
                .map_err(|e| library_failure(&e, "--save: ")),
        }
    }

    /// Stores the finished job as a plan, in one transaction.
    ///
    /// # Errors
    /// The library refused or failed (output, usage for a refused name): the run's outputs are
    /// already written, the plan is not saved.
    pub fn save(
        &self,
        scan: &Scan,
        spec: &JobSpec,
        finished: &Finished,
    ) -> Result<PlanInfo, Failure> {
        let plan = NewPlan {
            name: &self.name,
            note: &self.note,
            spec,
            finished,
        };
        self.library
            .save(scan, self.label.as_deref(), plan)
            .map_err(|e| {
                library_failure(
                    &e,
                    "the run's outputs were written but the plan was not saved in the case library: ",
                )
            })
    }

    /// The database file, for the message.
    pub fn database_path(&self) -> PathBuf {
        self.library.database_path()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_the_library_would_refuse_are_refused_up_front() {
        assert!(check_name("--save", "first plan").is_ok());
        assert!(check_name("--save", &"é".repeat(200)).is_ok());
        for bad in ["", "   ", "a\nb", "tab\there", &"x".repeat(201)] {
            let f = check_name("--save", bad).unwrap_err();
            assert_eq!(f.code, Exit::Usage, "{bad:?}");
            assert!(f.message.starts_with("--save "), "{}", f.message);
        }
        assert!(check_note("").is_ok());
        assert!(check_note("line one\nline two\tand a tab").is_ok());
        assert_eq!(check_note("bell\u{7}").unwrap_err().code, Exit::Usage);
        assert_eq!(
            check_note(&"n".repeat(10_001)).unwrap_err().code,
            Exit::Usage
        );
    }
}
