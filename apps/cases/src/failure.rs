//! Why the program stops: the case library's errors as the exit-code table's codes, with their
//! message.

use tissue_cases::CaseError;

pub use tissue_cli::{Exit, Failure};

/// The exit code of a library error (documented in `--help`): a bad name or no data folder is
/// the command line's; an id not in the library or an archive that cannot be imported is an
/// input's; anything else is the library's (the output code).
pub fn exit_of(e: &CaseError) -> Exit {
    match e {
        CaseError::NoDataDir | CaseError::Invalid { .. } => Exit::Usage,
        CaseError::NotFound { .. } | CaseError::Archive { .. } => Exit::Input,
        CaseError::Open { .. }
        | CaseError::Newer { .. }
        | CaseError::Database { .. }
        | CaseError::Damaged { .. }
        | CaseError::Plan(_)
        | CaseError::Write { .. } => Exit::Output,
    }
}

/// A library error as the program's failure.
pub fn from_case(e: &CaseError) -> Failure {
    Failure::new(exit_of(e), e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn library_errors_map_to_the_documented_codes() {
        let not_found = CaseError::NotFound {
            what: "plan",
            id: "c00".into(),
        };
        assert_eq!(from_case(&not_found).code, Exit::Input);
        assert!(from_case(&not_found).message.contains("tissue-cases list"));
        let invalid = CaseError::Invalid {
            field: "name",
            message: "empty".into(),
        };
        assert_eq!(exit_of(&invalid), Exit::Usage);
        let open = CaseError::Open {
            path: "/x".into(),
            source: std::io::Error::other("not a folder"),
        };
        assert_eq!(exit_of(&open), Exit::Output);
    }
}
