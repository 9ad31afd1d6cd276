//! The real `meshgen` binary with its standard output closed by the reader (unix: SIGPIPE).
#![cfg(unix)]

use std::process::Command;

/// `meshgen --help | head -0`: meshgen writes meshes to files, so clap's help, version and
/// subcommand help are all it prints on stdout. With the reader gone before the first write,
/// SIGPIPE ends it (status 141 in a shell) with nothing on stderr, like every tissue binary
/// (regression: the binaries panicked with "failed printing to stdout: Broken pipe").
#[test]
fn broken_pipe_ends_meshgen_quietly_by_sigpipe() {
    for args in [
        &["--help"][..],
        &["--version"],
        &["help", "sphere"],
        &["cube", "--help"],
    ] {
        let mut command = Command::new(env!("CARGO_BIN_EXE_meshgen"));
        command.args(args);
        tissue_cli::testing::close_stdout_after(command, 0).assert_killed_by_sigpipe();
    }
}
