//! The exit codes of every tissue binary: one table, so that a code means the same failure in
//! `insert`, `trainer`, `meshinfo`, `meshgen` and `studio`.

use std::process::ExitCode;

/// Why a tissue binary ended: its exit code. The same class of failure has the same code in every
/// binary; a binary uses the codes that can happen to it.
///
/// | code | variant | meaning |
/// |---|---|---|
/// | 0 | [`Exit::Success`] | success |
/// | 1 | [`Exit::Failure`] | another failure: the system refused something (a socket, a thread, the async runtime), or a bug |
/// | 2 | [`Exit::Usage`] | bad command line (clap's code too): unknown flag, bad value syntax, a missing argument |
/// | 3 | [`Exit::Input`] | an input file is missing, unreadable, or of an unsupported type |
/// | 4 | [`Exit::Mesh`] | an input mesh is malformed or invalid (defects) |
/// | 5 | [`Exit::Placement`] | the implant's placement or region does not fit the surface |
/// | 6 | [`Exit::Parameters`] | a parameter is out of range |
/// | 7 | [`Exit::Run`] | the simulation diverged or failed |
/// | 8 | [`Exit::Output`] | an output could not be written |
/// | 9 | [`Exit::Meshing`] | a surface cannot be tetrahedralised |
/// | 130 | [`Exit::Interrupted`] | interrupted (Ctrl-C); nothing was written |
///
/// 141 (128 + SIGPIPE, unix) is not returned but shown by the shell when standard output was
/// closed by its reader ([`crate::reset_sigpipe`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Exit {
    /// Success.
    Success = 0,
    /// Another failure: the system refused something (a socket, a thread, the async runtime), or
    /// a bug.
    Failure = 1,
    /// Bad command line: unknown flag, bad value syntax, a missing argument (clap exits with it
    /// too).
    Usage = 2,
    /// An input file is missing, unreadable, or of an unsupported type.
    Input = 3,
    /// An input mesh is malformed or invalid (defects).
    Mesh = 4,
    /// The implant's placement or region does not fit the surface: a point off the surface, a
    /// region empty, too small or too large.
    Placement = 5,
    /// A parameter is out of range.
    Parameters = 6,
    /// The simulation diverged or failed.
    Run = 7,
    /// An output could not be written.
    Output = 8,
    /// A surface cannot be tetrahedralised (open, non-manifold, inside out, …).
    Meshing = 9,
    /// Interrupted (Ctrl-C): the run was cancelled and nothing was written.
    Interrupted = 130,
}

impl Exit {
    /// Every code, in the table's order.
    pub const ALL: [Exit; 11] = [
        Exit::Success,
        Exit::Failure,
        Exit::Usage,
        Exit::Input,
        Exit::Mesh,
        Exit::Placement,
        Exit::Parameters,
        Exit::Run,
        Exit::Output,
        Exit::Meshing,
        Exit::Interrupted,
    ];

    /// The process's exit status.
    pub const fn code(self) -> u8 {
        self as u8
    }

    /// What the code means, for every binary (one line).
    pub const fn meaning(self) -> &'static str {
        match self {
            Exit::Success => "success",
            Exit::Failure => {
                "another failure: the system refused something (a socket, a thread, the async \
                 runtime), or a bug"
            }
            Exit::Usage => "bad command line: unknown flag, bad value syntax, a missing argument",
            Exit::Input => "an input file is missing, unreadable, or of an unsupported type",
            Exit::Mesh => "an input mesh is malformed or invalid (defects)",
            Exit::Placement => "the implant's placement or region does not fit the surface",
            Exit::Parameters => "a parameter is out of range",
            Exit::Run => "the simulation diverged or failed",
            Exit::Output => "an output could not be written",
            Exit::Meshing => "a surface cannot be tetrahedralised",
            Exit::Interrupted => "interrupted (Ctrl-C): the run was cancelled, nothing was written",
        }
    }

    /// The `EXIT CODES` section of a binary's `--help`: the shared table, with `details` (what the
    /// code means in this binary) after the meaning of the codes they name.
    pub fn help_section(details: &[(Exit, &str)]) -> String {
        let mut s = String::from("EXIT CODES (the same table for every tissue binary):\n");
        for exit in Exit::ALL {
            s.push_str(&format!("  {:<4} {}", exit.code(), exit.meaning()));
            for (_, d) in details.iter().filter(|(e, _)| *e == exit) {
                s.push_str(": ");
                s.push_str(d);
            }
            s.push('\n');
        }
        s.push_str(
            "  141  (unix, shown by the shell) stdout closed by its reader (| head): SIGPIPE ends \
             the program at its next write to stdout, silently",
        );
        s
    }
}

impl From<Exit> for ExitCode {
    fn from(exit: Exit) -> Self {
        ExitCode::from(exit.code())
    }
}

impl std::fmt::Display for Exit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} ({})", self.code(), self.meaning())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_distinct_and_documented() {
        let mut codes: Vec<u8> = Exit::ALL.iter().map(|e| e.code()).collect();
        codes.sort_unstable();
        codes.dedup();
        assert_eq!(codes.len(), Exit::ALL.len());
        // The fixed points every binary and script relies on.
        assert_eq!(Exit::Success.code(), 0);
        assert_eq!(
            Exit::Usage.code(),
            2,
            "clap's own code for a bad command line"
        );
        assert_eq!(Exit::Interrupted.code(), 130, "128 + SIGINT");
        let help = Exit::help_section(&[(Exit::Placement, "point off the surface")]);
        for exit in Exit::ALL {
            let line = format!("  {:<4} {}", exit.code(), exit.meaning());
            assert!(help.contains(&line), "{help}");
        }
        assert!(help.contains("does not fit the surface: point off the surface"));
        assert!(help.contains("141"));
    }
}
