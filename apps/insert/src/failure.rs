//! Why the program stops: a one-line message that says what to change, and its exit code.
//! The planner's error kinds map to the documented codes; its messages name request fields,
//! shown here as the flags that set them.

use tissue_planner::{ErrorKind, PlanError};

use crate::cli::flag_of;

/// The exit codes: the table every tissue binary shares (see `insert --help`).
pub use tissue_cli::Exit;

/// A reason to stop with a non-zero exit code.
#[derive(Debug, Clone, PartialEq)]
pub struct Failure {
    /// The exit code.
    pub code: Exit,
    /// What went wrong and what to change, on one line.
    pub message: String,
}

impl Failure {
    /// A failure with `code` and `message`.
    pub fn new(code: Exit, message: impl Into<String>) -> Self {
        Failure {
            code,
            message: message.into(),
        }
    }

    /// The message on one line.
    pub fn line(&self) -> String {
        self.message
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// The planner's error, its fields named by their flags.
    pub fn from_plan(e: &PlanError) -> Self {
        let code = match e.kind {
            ErrorKind::Usage => Exit::Usage,
            ErrorKind::Input => Exit::Input,
            ErrorKind::Mesh => Exit::Mesh,
            ErrorKind::Placement => Exit::Placement,
            ErrorKind::Parameters => Exit::Parameters,
            ErrorKind::Run => Exit::Run,
            ErrorKind::Output => Exit::Output,
            ErrorKind::Cancelled => Exit::Interrupted,
        };
        Failure::new(code, e.message_with(flag_of))
    }

    /// Writing an output failed.
    pub fn output(what: &str, e: impl std::fmt::Display) -> Self {
        Failure::new(
            Exit::Output,
            format!("cannot write the {what}: {e}; check the folder exists and is writable"),
        )
    }

    /// Ctrl-C.
    pub fn interrupted(steps: u64) -> Self {
        Failure::new(
            Exit::Interrupted,
            format!("interrupted after {steps} steps; nothing was written"),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_map_to_the_exit_code_table_and_fields_to_flags() {
        let e = PlanError::field(
            ErrorKind::Placement,
            "region_radius_cm",
            "use a smaller `region_radius_cm` or implant",
        );
        let f = Failure::from_plan(&e);
        assert_eq!(f.code, Exit::Placement);
        assert_eq!(f.line(), "use a smaller --radius or implant");
        let v = PlanError::field(ErrorKind::Parameters, "volume_cm3", "`volume_cm3` < 0");
        assert_eq!(Failure::from_plan(&v).code, Exit::Parameters);
        assert_eq!(Failure::from_plan(&v).message, "--volume < 0");
    }
}
