//! Why the program stops: a one-line message that says what to change, and its exit code.
//! The planner's error kinds map to the documented codes; its messages name request fields,
//! shown here as the flags that set them.

use tissue_planner::{ErrorKind, PlanError};

use crate::cli::flag_of;

/// The exit codes (the table every tissue binary shares, see `insert --help`) and the reason
/// to stop, with its one-line message: tissue-cli's, the same as `trainer`'s.
pub use tissue_cli::{Exit, Failure};

/// The planner's errors as `insert` shows them.
pub trait FromPlan {
    /// The planner's error, its fields named by their flags, with the exit code of its kind.
    fn from_plan(e: &PlanError) -> Self;
}

impl FromPlan for Failure {
    fn from_plan(e: &PlanError) -> Self {
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
