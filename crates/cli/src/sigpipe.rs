//! The default SIGPIPE disposition, restored.

/// Restores the default disposition of SIGPIPE, so that a write to a closed pipe ends the program
/// silently (status 141 in a shell) instead of making `println!` panic. Call it first in `main`.
/// Does nothing on platforms without signals.
pub fn reset_sigpipe() {
    #[cfg(unix)]
    default_sigpipe();
}

#[cfg(unix)]
#[allow(unsafe_code)]
fn default_sigpipe() {
    // SAFETY: `signal` with a valid signal number and `SIG_DFL` only changes how the kernel treats
    // a write to a pipe that has no reader (end the process instead of failing with EPIPE). No
    // handler runs, no memory is touched, and nothing in Rust's runtime relies on SIGPIPE being
    // ignored: std only ignores it at start-up so that such writes return errors. The result
    // (the previous disposition, or SIG_ERR for an invalid signal number) is not needed.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
