//! Why the program stops: a one-line message that says what to change, and its exit code.
//! The planner's error kinds map to the documented codes; its messages name request fields,
//! shown here as the flags that set them.

use tissue_planner::{ErrorKind, PlanError};

use crate::cli::flag_of;

/// The documented exit codes (see `insert --help`).
pub mod code {
    /// Usage: clap's code for a bad command line.
    pub const USAGE: u8 = 2;
    /// The input file is missing, unreadable or of an unsupported type.
    pub const INPUT: u8 = 3;
    /// The mesh is malformed or invalid.
    pub const MESH: u8 = 4;
    /// The point is off the surface, or the region is empty, too large or too small.
    pub const PLACEMENT: u8 = 5;
    /// An implant or tissue parameter is out of range.
    pub const PARAMETERS: u8 = 6;
    /// The run diverged or failed.
    pub const RUN: u8 = 7;
    /// An output could not be written.
    pub const OUTPUT: u8 = 8;
    /// Interrupted by Ctrl-C.
    pub const INTERRUPTED: u8 = 130;
}

/// A reason to stop with a non-zero exit code.
#[derive(Debug, Clone, PartialEq)]
pub struct Failure {
    /// The exit code.
    pub code: u8,
    /// What went wrong and what to change, on one line.
    pub message: String,
}

impl Failure {
    /// A failure with `code` and `message`.
    pub fn new(code: u8, message: impl Into<String>) -> Self {
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
            ErrorKind::Usage => code::USAGE,
            ErrorKind::Input => code::INPUT,
            ErrorKind::Mesh => code::MESH,
            ErrorKind::Placement => code::PLACEMENT,
            ErrorKind::Parameters => code::PARAMETERS,
            ErrorKind::Run => code::RUN,
            ErrorKind::Output => code::OUTPUT,
            ErrorKind::Cancelled => code::INTERRUPTED,
        };
        Failure::new(code, e.message_with(flag_of))
    }

    /// Writing an output failed.
    pub fn output(what: &str, e: impl std::fmt::Display) -> Self {
        Failure::new(
            code::OUTPUT,
            format!("cannot write the {what}: {e}; check the folder exists and is writable"),
        )
    }

    /// Ctrl-C.
    pub fn interrupted(steps: u64) -> Self {
        Failure::new(
            code::INTERRUPTED,
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
        assert_eq!(f.code, code::PLACEMENT);
        assert_eq!(f.line(), "use a smaller --radius or implant");
        let v = PlanError::field(ErrorKind::Parameters, "volume_cm3", "`volume_cm3` < 0");
        assert_eq!(Failure::from_plan(&v).code, code::PARAMETERS);
        assert_eq!(Failure::from_plan(&v).message, "--volume < 0");
    }
}
