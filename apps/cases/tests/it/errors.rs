//! Each error's exit code and message, and the commands on a folder with no library.

use super::*;
use tissue_cli::Exit;

#[test]
fn a_folder_with_no_library_lists_nothing_and_is_not_made() {
    let dir = scratch("empty");
    let data = dir.join("none yet");
    assert_eq!(stdout(&ok(&data, &["list", "--json"])), "[]\n");
    let o = ok(&data, &["list"]);
    assert!(stdout(&o).is_empty());
    assert!(stderr(&o).contains("no patients"), "{}", stderr(&o));
    assert_eq!(stdout(&ok(&data, &["check"])), "ok\n");
    let id = "c0123456789abcdef0123456789abcdef";
    fails(
        &data,
        &["show", id],
        Exit::Input,
        &["no plan", id, "tissue-cases list"],
    );
    fails(
        &data,
        &["erase", "p01", "--yes"],
        Exit::Input,
        &["no patient"],
    );
    assert!(!data.exists(), "a command that only reads made the library");
}

/// Without --data the library is the platform's data folder: `$XDG_DATA_HOME/tissue` on Linux
/// (a scratch folder here).
#[cfg(target_os = "linux")]
#[test]
fn the_default_library_is_in_the_data_folder() {
    let dir = scratch("default");
    let o = cases()
        .arg("list")
        .env("XDG_DATA_HOME", &*dir)
        .env("HOME", &*dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let expected = format!("no patients in {}", dir.join("tissue").display());
    assert!(stderr(&o).contains(&expected), "{}", stderr(&o));
}

#[test]
fn each_error_has_its_exit_code_and_a_message_that_says_what_to_change() {
    let dir = scratch("errors");
    let data = dir.join("library");
    fails(&data, &["show", "x01"], Exit::Usage, &["\"x01\"", "p", "c"]);
    fails(
        &data,
        &["delete", "p01"],
        Exit::Usage,
        &["patient's id", "plan's"],
    );
    fails(
        &data,
        &["export", "c01", "--out", "x.zip"],
        Exit::Usage,
        &["plan's id"],
    );
    // --data on a file.
    let file = dir.join("a-file");
    std::fs::write(&file, "keep").unwrap();
    for args in [&["list"][..], &["check"], &["show", "c01"]] {
        fails(&file, args, Exit::Output, &["a-file", "--data"]);
    }
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "keep");
    // clap's own usage errors.
    let o = cases().args(["erase"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let o = cases()
        .args(["show", "c01", "--json", "--report"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let o = cases().output().unwrap();
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn help_documents_the_ids_the_data_folder_and_the_exit_codes() {
    let o = cases().arg("--help").output().unwrap();
    assert!(o.status.success());
    // Its lines are wrapped to the terminal: compare with white space runs as one space.
    let help = stdout(&o).split_whitespace().collect::<Vec<_>>().join(" ");
    for needle in [
        "EXIT CODES",
        "no patient or plan of that id (not found)",
        "without --yes",
        "~/.local/share/tissue",
        "unique beginning",
        "docs/cases.md",
    ] {
        assert!(help.contains(needle), "no {needle:?} in:\n{help}");
    }
    for command in [
        "list", "show", "export", "import", "rename", "note", "delete", "erase", "check",
    ] {
        assert!(
            help.contains(&format!(" {command} ")),
            "no {command} in:\n{help}"
        );
    }
}

/// `tissue-cases --help | head -0`: ended by SIGPIPE, nothing on stderr.
#[cfg(unix)]
#[test]
fn broken_pipe_ends_tissue_cases_quietly_by_sigpipe() {
    let mut command = cases();
    command.arg("--help");
    tissue_cli::testing::close_stdout_after(command, 0).assert_quiet();
}
