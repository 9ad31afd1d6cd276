//! The command line: the subcommands, their flags, and the long help with the ids, the data
//! folder and the exit codes.

use std::path::PathBuf;

use clap::{Parser, Subcommand};
use tissue_cli::Exit;

const ABOUT: &str = "The case library from the command line: the patients (their scans) and \
the plans run on them, as `insert --save` and the studio store them.";

const LONG_ABOUT: &str = "\
The case library from the command line: the patients (their scans) and the plans run on them, \
as `insert --save NAME` and the studio store them, in one embedded SQLite database \
(cases.sqlite in the data folder). List and search them, show a plan's report byte for byte, \
export a patient's case as one zip and import it on another computer, rename, annotate, delete \
a plan, erase a patient for good, and check the database.

IDS. A patient's id is `p` and 32 hex digits, a plan's `c` and 32 hex digits (`tissue-cases \
list` shows them). Any unique beginning of one is enough: `tissue-cases show c3f9a`.

THE DATA FOLDER. --data DIR, or the platform's data folder: $XDG_DATA_HOME/tissue or \
~/.local/share/tissue on Linux, ~/Library/Application Support/tissue on macOS, %APPDATA%\\tissue \
on Windows. The folder is made with mode 0700 and the database 0600. A command that only reads \
does not make it: `list` of a folder with no library lists nothing.

Examples:
  insert --save \"first plan\" --report first.json
  tissue-cases list
  tissue-cases show c3f9a --report > again.json      (equal to first.json)
  tissue-cases export p81d0 --out case.zip
  tissue-cases --data /mnt/other import case.zip
  tissue-cases erase p81d0 --yes";

/// The text after the options in `--help`: the exit codes, with what each means here.
fn after_long_help() -> String {
    format!(
        "The guide: docs/cases.md.\n\n{}",
        Exit::help_section(&[
            (
                Exit::Usage,
                "an id that starts with neither p nor c or fits several, an empty or too long \
                 name, `erase` without --yes (nothing is erased), no data folder",
            ),
            (
                Exit::Input,
                "no patient or plan of that id (not found); the archive to import is missing, \
                 unreadable, damaged, foreign or too large",
            ),
            (
                Exit::Output,
                "the case library: --data is not a usable folder, the database was written by a \
                 newer tissue, failed (disk full, locked) or holds damaged data, `check` found \
                 it unsound; the export file cannot be written",
            ),
        ])
    )
}

/// `tissue-cases`: the command line.
#[derive(Debug, Parser)]
#[command(
    name = "tissue-cases",
    version,
    about = ABOUT,
    long_about = LONG_ABOUT,
    after_long_help = after_long_help(),
    after_help = "Ids, the data folder, examples and the exit codes: tissue-cases --help"
)]
pub struct Cli {
    /// The case library's folder [default: the platform's data folder, ~/.local/share/tissue
    /// on Linux].
    #[arg(long, value_name = "DIR", global = true)]
    pub data: Option<PathBuf>,

    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// The patients, newest plan first, each with its plans (id, name, mode, when run, area
    /// gain).
    List {
        /// Only the patients whose label contains TEXT (case-insensitive).
        #[arg(long, value_name = "TEXT")]
        search: Option<String>,
        /// JSON: an array of {"patient": {…}, "plans": [{…}, …]}.
        #[arg(long)]
        json: bool,
    },
    /// A patient (its scan and plans) or a plan (its figures and report).
    Show {
        /// A patient (p…) or plan (c…) id, or a unique beginning of one.
        id: String,
        /// JSON: a patient as {"patient", "plans"}; a plan as {"plan", "patient", "job",
        /// "report"}.
        #[arg(long, conflicts_with = "report")]
        json: bool,
        /// A plan's report JSON only, byte for byte as the planner wrote it (what `insert
        /// --report` wrote for the same run).
        #[arg(long)]
        report: bool,
    },
    /// A patient's case as one zip (the scan, every plan's job, report and result), written
    /// atomically.
    Export {
        /// The patient (p…).
        patient: String,
        /// The zip to write.
        #[arg(long, value_name = "FILE.zip")]
        out: PathBuf,
    },
    /// A case zip made by `export` (here or on another computer): every file's hash checked,
    /// in one transaction; plans already in the library are left as they are.
    Import {
        /// The zip.
        #[arg(value_name = "FILE.zip")]
        file: PathBuf,
        /// JSON: {"patient", "plans_added", "plans_skipped"}.
        #[arg(long)]
        json: bool,
    },
    /// Renames a plan (c…) or relabels a patient (p…).
    Rename {
        /// The plan or patient.
        id: String,
        /// The new name (1 to 200 characters, one line).
        name: String,
    },
    /// Sets a plan's note ("" clears it).
    Note {
        /// The plan (c…).
        plan: String,
        /// The note (up to 10000 characters).
        text: String,
    },
    /// Deletes a plan (its patient and other plans stay).
    Delete {
        /// The plan (c…).
        plan: String,
    },
    /// Erases a patient for good: the patient, every plan and the scan, overwritten in every
    /// file of the library (secure delete, WAL checkpoint, vacuum). Cannot be undone.
    Erase {
        /// The patient (p…).
        patient: String,
        /// Yes, erase it (without it nothing is erased and what would be is said).
        #[arg(long)]
        yes: bool,
    },
    /// The database's integrity check (SQLite's): exits non-zero when it is not sound.
    Check,
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn the_command_is_well_formed() {
        Cli::command().debug_assert();
    }

    #[test]
    fn data_is_taken_before_or_after_the_subcommand() {
        let a = Cli::try_parse_from(["tissue-cases", "--data", "/x", "list"]).unwrap();
        let b = Cli::try_parse_from(["tissue-cases", "list", "--data", "/x"]).unwrap();
        assert_eq!(a.data, b.data);
        assert!(Cli::try_parse_from(["tissue-cases", "show", "c1", "--json", "--report"]).is_err());
    }
}
