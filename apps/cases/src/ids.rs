//! The library opened as a command needs it, and the ids a user types: `p…` a patient, `c…` a
//! plan, in full or by a unique beginning.

use std::path::{Path, PathBuf};

use tissue_cases::{CaseError, Library, DATABASE_FILE};

use crate::failure::{from_case, Exit, Failure};

/// A full id: the prefix letter and 32 hex digits.
const FULL_ID_LEN: usize = 33;

/// What an id names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `p…`.
    Patient,
    /// `c…`.
    Plan,
}

impl Kind {
    /// The library's word for it.
    pub fn word(self) -> &'static str {
        match self {
            Kind::Patient => "patient",
            Kind::Plan => "plan",
        }
    }
}

/// The kind of `id` by its first letter.
///
/// # Errors
/// An id that starts with neither `p` nor `c` (usage).
pub fn kind(id: &str) -> Result<Kind, Failure> {
    match id.chars().next() {
        Some('p') => Ok(Kind::Patient),
        Some('c') => Ok(Kind::Plan),
        _ => Err(Failure::new(
            Exit::Usage,
            format!(
                "{id:?} is not an id: a patient's starts with p, a plan's with c; list them with \
                 `tissue-cases list`"
            ),
        )),
    }
}

/// `id` of kind `want`.
///
/// # Errors
/// An id of the other kind or of neither (usage).
pub fn expect(id: &str, want: Kind) -> Result<(), Failure> {
    let got = kind(id)?;
    if got != want {
        return Err(Failure::new(
            Exit::Usage,
            format!(
                "{id:?} is a {}'s id; this command takes a {}'s ({})",
                got.word(),
                want.word(),
                match want {
                    Kind::Patient => "p…",
                    Kind::Plan => "c…",
                }
            ),
        ));
    }
    Ok(())
}

/// The library's folder: `--data` or the platform's.
///
/// # Errors
/// No data folder on this computer (usage: give --data).
pub fn data_dir(data: Option<&Path>) -> Result<PathBuf, Failure> {
    match data {
        Some(d) => Ok(d.to_path_buf()),
        None => tissue_cases::default_data_dir().map_err(|e| from_case(&e)),
    }
}

/// The library in `dir`, made when new.
///
/// # Errors
/// A folder that cannot be made or opened, a newer or failing database (output).
pub fn open(dir: &Path) -> Result<Library, Failure> {
    Library::open(dir).map_err(|e| from_case(&e))
}

/// The library in `dir` if there is one: `None` for a folder that does not exist or has no
/// database, so that a command that only reads makes nothing. A path that is not a folder is
/// opened, for the library's error.
///
/// # Errors
/// As [`open`].
pub fn open_existing(dir: &Path) -> Result<Option<Library>, Failure> {
    let absent = !dir.exists() || (dir.is_dir() && !dir.join(DATABASE_FILE).exists());
    if absent {
        return Ok(None);
    }
    open(dir).map(Some)
}

/// The error for an id asked of a folder with no library.
pub fn not_found(kind: Kind, id: &str) -> Failure {
    from_case(&CaseError::NotFound {
        what: kind.word(),
        id: id.to_owned(),
    })
}

/// The full id that `id` (full, or a beginning of one) names.
///
/// # Errors
/// An id of the wrong kind or that fits several (usage), or none (not found: input).
pub fn resolve(library: &Library, id: &str, want: Kind) -> Result<String, Failure> {
    expect(id, want)?;
    if id.len() >= FULL_ID_LEN {
        return Ok(id.to_owned());
    }
    let patients = library.patients(None).map_err(|e| from_case(&e))?;
    let mut found: Vec<String> = Vec::new();
    for patient in &patients {
        match want {
            Kind::Patient => {
                if patient.uid.starts_with(id) {
                    found.push(patient.uid.clone());
                }
            }
            Kind::Plan => {
                let plans = library.plans(&patient.uid).map_err(|e| from_case(&e))?;
                found.extend(
                    plans
                        .into_iter()
                        .filter(|p| p.uid.starts_with(id))
                        .map(|p| p.uid),
                );
            }
        }
    }
    match found.len() {
        0 => Err(not_found(want, id)),
        1 => Ok(found.remove(0)),
        n => Err(Failure::new(
            Exit::Usage,
            format!(
                "{id:?} is the beginning of {n} {}s' ids ({}); give more of it",
                want.word(),
                found.join(", ")
            ),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_id_names_its_kind_by_its_first_letter() {
        assert_eq!(kind("p0a").unwrap(), Kind::Patient);
        assert_eq!(kind("c0a").unwrap(), Kind::Plan);
        assert_eq!(kind("x0a").unwrap_err().code, Exit::Usage);
        assert_eq!(kind("").unwrap_err().code, Exit::Usage);
        assert!(expect("c0a", Kind::Plan).is_ok());
        let wrong = expect("p0a", Kind::Plan).unwrap_err();
        assert_eq!(wrong.code, Exit::Usage);
        assert!(wrong.message.contains("patient's id"), "{}", wrong.message);
    }
}
