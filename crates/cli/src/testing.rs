//! Runs a real binary with its standard output closed under it (unix, feature `testing`).
//!
//! Test support only: a set-up that fails here is a failed test, so it panics with the reason.
#![allow(clippy::expect_used, clippy::panic)]

use std::io::{BufRead, BufReader, Read};
use std::os::unix::process::ExitStatusExt;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::thread;
use std::time::{Duration, Instant};

/// How long a program may take to end once its reader has gone.
const TIMEOUT: Duration = Duration::from_secs(120);

/// How a program ended whose standard output was closed by its reader.
#[derive(Debug)]
pub struct Ended {
    /// The command, for messages.
    pub command: String,
    /// What the reader read before it closed the pipe: at most the lines it was asked for.
    pub read: String,
    /// How the program ended.
    pub status: ExitStatus,
    /// Everything the program wrote on standard error.
    pub stderr: String,
}

impl Ended {
    /// Whether the kernel ended the program at a write to the closed pipe (status 141 in a shell).
    pub fn killed_by_sigpipe(&self) -> bool {
        self.status.signal() == Some(libc::SIGPIPE)
    }

    /// Panics unless the program ended quietly: nothing on standard error (no "panicked", no
    /// "Broken pipe"), and either success (it wrote everything before the reader went) or death
    /// by SIGPIPE.
    pub fn assert_quiet(&self) {
        assert!(
            self.stderr.is_empty(),
            "{}: wrote on stderr after its stdout was closed ({}):\n{}",
            self.command,
            self.status,
            self.stderr
        );
        assert!(
            self.status.success() || self.killed_by_sigpipe(),
            "{}: ended with {} after its stdout was closed, not success or SIGPIPE",
            self.command,
            self.status
        );
    }

    /// Panics unless the program ended quietly and by SIGPIPE: what a program that writes to
    /// standard output does under [`reset_sigpipe`](crate::reset_sigpipe) when the reader has
    /// gone before it writes (`close_stdout_after(command, 0)`).
    pub fn assert_killed_by_sigpipe(&self) {
        self.assert_quiet();
        assert!(
            self.killed_by_sigpipe(),
            "{}: ended with {} after its stdout was closed, not by SIGPIPE",
            self.command,
            self.status
        );
    }
}

/// Runs `command` with standard output a pipe whose reader reads `lines` lines and then closes
/// it, and waits (at most two minutes) for the program to end. With `lines == 0` the reader has
/// gone before the program starts, so its first write to standard output meets a closed pipe.
/// With `lines > 0` the program's later writes meet the closed pipe if it prints more than the
/// pipe holds (64 KiB on Linux) after those lines, or writes after the reader has gone.
pub fn close_stdout_after(mut command: Command, lines: usize) -> Ended {
    let name = format!("{command:?}");
    command.stdin(Stdio::null()).stderr(Stdio::piped());
    if lines == 0 {
        // A pipe without a reader: `true` holds its read end and exits without reading.
        let mut reader = Command::new("true")
            .stdin(Stdio::piped())
            .spawn()
            .expect("`true` runs");
        let write_end = reader.stdin.take().expect("a pipe to `true`");
        reader.wait().expect("`true` ends");
        command.stdout(write_end);
    } else {
        command.stdout(Stdio::piped());
    }
    let mut child = command
        .spawn()
        .unwrap_or_else(|e| panic!("{name} does not start: {e}"));
    drop(command); // our copy of a write end
    let mut stderr = child.stderr.take().expect("stderr is piped");
    let stderr = thread::spawn(move || {
        let mut text = String::new();
        let _ = stderr.read_to_string(&mut text);
        text
    });
    let mut read = String::new();
    if let Some(stdout) = child.stdout.take() {
        let mut stdout = BufReader::new(stdout);
        for _ in 0..lines {
            match stdout.read_line(&mut read) {
                Ok(0) | Err(_) => break,
                Ok(_) => {}
            }
        }
    } // the read end closes here
    let status = wait(&mut child, &name);
    Ended {
        command: name,
        read,
        status,
        stderr: stderr.join().expect("the stderr reader ends"),
    }
}

/// Waits for `child` to end, killing it (and panicking) after [`TIMEOUT`].
fn wait(child: &mut Child, name: &str) -> ExitStatus {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().expect("the child can be waited for") {
            return status;
        }
        if start.elapsed() > TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{name} did not end within {TIMEOUT:?} after its stdout was closed");
        }
        thread::sleep(Duration::from_millis(5));
    }
}
