//! # tissue-cli: what the tissue binaries share at the edge of the process
//!
//! ## Brief overview
//! - [`Exit`]: the exit codes of every binary, one table (`insert`, `trainer`, `meshinfo`,
//!   `meshgen` and `studio` all return them; [`Exit::help_section`] is their `--help`'s table).
//! - [`Failure`]: why a binary stops, an [`Exit`] code and a message that says what to change
//!   ([`Failure::line`] is what it prints on standard error); the failures every binary has
//!   ([`Failure::output`], [`Failure::interrupted`]) are written here once.
//! - [`reset_sigpipe`]: the first call in every binary's `main`. Rust's runtime starts programs
//!   with SIGPIPE ignored, so a write to a pipe whose reader has gone (`meshinfo FILE | head`)
//!   fails with `EPIPE` and `println!` panics with "failed printing to stdout: Broken pipe".
//!   With the default disposition restored, the kernel ends the program at that write, silently,
//!   as it ends `cat` or `grep`: the shell reports status 141 (128 + SIGPIPE). This covers every
//!   write to standard output at once: `println!` anywhere in a binary, on any thread, and clap's
//!   `--help` and `--version`. On other platforms it does nothing.
//! - `testing` (feature `testing`, unix only): `testing::close_stdout_after` runs a real binary
//!   whose reader closes the pipe after a few lines (or before the program starts), and
//!   `testing::Ended::assert_quiet` checks that it ended quietly: nothing on standard error, and
//!   success or death by SIGPIPE. The apps' CLI tests use it.
//!
//! The program is ended where it writes, without unwinding: the binaries only print to standard
//! output outside their file writes, and every file they write is atomic (a temporary file, then
//! a rename), so a closed pipe never leaves half a file behind.
//!
//! ```
//! // First thing in `main`:
//! tissue_cli::reset_sigpipe();
//! println!("from here on, a closed pipe ends this program quietly");
//! ```

mod exit;
mod failure;
mod sigpipe;
#[cfg(all(unix, feature = "testing"))]
pub mod testing;

pub use crate::exit::Exit;
pub use crate::failure::Failure;
pub use crate::sigpipe::reset_sigpipe;
