//! Why a binary stops: a message that says what to change, and its exit code.

use crate::Exit;

/// A reason for a binary to stop with a non-zero exit code: the code of the shared table
/// ([`Exit`]) and a message that says what went wrong and what to change. The binary prints
/// [`Failure::line`] on standard error and returns the code; each binary maps its libraries'
/// errors to it (their kinds to codes, their fields to its flags).
#[derive(Debug, Clone, PartialEq)]
pub struct Failure {
    /// The exit code.
    pub code: Exit,
    /// What went wrong and what to change.
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

    /// The message on one line: every run of white space (a line break in a long message
    /// included) as one space.
    pub fn line(&self) -> String {
        self.message
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// Writing an output (`what`: "report", "frame 25", a path) failed with `e`.
    pub fn output(what: &str, e: impl std::fmt::Display) -> Self {
        Failure::new(
            Exit::Output,
            format!("cannot write the {what}: {e}; check the folder exists and is writable"),
        )
    }

    /// Interrupted (Ctrl-C) after `steps` steps, before anything was written.
    pub fn interrupted(steps: u64) -> Self {
        Failure::new(
            Exit::Interrupted,
            format!("interrupted after {steps} steps; nothing was written"),
        )
    }
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.line())
    }
}

impl std::error::Error for Failure {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failure_is_its_code_and_its_message_on_one_line() {
        let f = Failure::new(Exit::Parameters, "a depth of -1 cm:\n   give a depth ≥ 0");
        assert_eq!(f.code, Exit::Parameters);
        assert_eq!(f.line(), "a depth of -1 cm: give a depth ≥ 0");
        assert_eq!(f.to_string(), f.line());
        assert_eq!(f.clone(), f);
    }

    #[test]
    fn the_shared_failures_say_what_to_do() {
        let f = Failure::output("report", "permission denied");
        assert_eq!(f.code, Exit::Output);
        assert_eq!(
            f.message,
            "cannot write the report: permission denied; check the folder exists and is writable"
        );
        let f = Failure::interrupted(42);
        assert_eq!(f.code, Exit::Interrupted);
        assert_eq!(f.message, "interrupted after 42 steps; nothing was written");
    }
}
