//! The conventions every entry point follows: the status enum, the thread-local last error, the
//! panic guard, and the checked conversions from C pointers.

use std::any::Any;
use std::cell::RefCell;
use std::ffi::{c_char, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};

use tissue_planner::{ErrorKind, PlanError};
use tissue_scenes::{SceneError, SceneErrorKind};

/// What a call did. `TISSUE_OK` is 0; every other value comes with a message
/// (`tissue_last_error`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum tissue_status {
    /// Done.
    TISSUE_OK = 0,
    /// A pointer argument that must not be NULL was NULL.
    TISSUE_NULL_ARGUMENT = 1,
    /// An argument is out of range or malformed (a bad enum value, text that is not UTF-8, a
    /// non-finite number, an unknown tool, a result of another kind of job).
    TISSUE_INVALID_ARGUMENT = 2,
    /// The caller's buffer is too small: query the size first (the message says how large).
    TISSUE_BUFFER_TOO_SMALL = 3,
    /// A file is missing, unreadable or of an unsupported type.
    TISSUE_INPUT = 4,
    /// A mesh file is malformed or its mesh invalid (the message names the line or element).
    TISSUE_INVALID_MESH = 5,
    /// A planning request is incomplete (a missing placement or shape size).
    TISSUE_USAGE = 6,
    /// The implant's point is off the surface, or its region is empty, too large or at the
    /// scan's border.
    TISSUE_PLACEMENT = 7,
    /// An implant, tissue or run parameter is out of range (the message names the field).
    TISSUE_PARAMETERS = 8,
    /// A planning run diverged or failed.
    TISSUE_RUN = 9,
    /// An output could not be written.
    TISSUE_OUTPUT = 10,
    /// The job was cancelled.
    TISSUE_CANCELLED = 11,
    /// The wait timed out: the job is still running.
    TISSUE_TIMEOUT = 12,
    /// There is nothing to read yet (a job still running).
    TISSUE_NOT_READY = 13,
    /// The trainer's simulation diverged, or a cut, suture or tool action failed.
    TISSUE_SIMULATION = 14,
    /// A bug: the library panicked. The panic was caught (nothing unwinds into the caller);
    /// the handle involved may be inconsistent: free it.
    TISSUE_PANIC = 15,
}

use tissue_status::*;

/// An error on its way to the caller: a status and its message.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Error {
    pub status: tissue_status,
    pub message: String,
}

impl Error {
    pub fn new(status: tissue_status, message: impl Into<String>) -> Self {
        Error {
            status,
            message: message.into(),
        }
    }

    pub fn invalid(message: impl Into<String>) -> Self {
        Error::new(TISSUE_INVALID_ARGUMENT, message)
    }

    pub fn null(name: &str) -> Self {
        Error::new(
            TISSUE_NULL_ARGUMENT,
            format!("`{name}` is NULL: pass a valid pointer"),
        )
    }
}

impl From<PlanError> for Error {
    fn from(e: PlanError) -> Self {
        let status = match e.kind {
            ErrorKind::Usage => TISSUE_USAGE,
            ErrorKind::Input => TISSUE_INPUT,
            ErrorKind::Mesh => TISSUE_INVALID_MESH,
            ErrorKind::Placement => TISSUE_PLACEMENT,
            ErrorKind::Parameters => TISSUE_PARAMETERS,
            ErrorKind::Run => TISSUE_RUN,
            ErrorKind::Output => TISSUE_OUTPUT,
            ErrorKind::Cancelled => TISSUE_CANCELLED,
        };
        Error::new(status, e.message)
    }
}

/// The status of a scene error's kind: the one place the C ABI maps them.
pub(crate) fn status_of(kind: SceneErrorKind) -> tissue_status {
    match kind {
        SceneErrorKind::Input => TISSUE_INPUT,
        SceneErrorKind::Mesh | SceneErrorKind::Meshing | SceneErrorKind::TooLarge => {
            TISSUE_INVALID_MESH
        }
        SceneErrorKind::Parameters | SceneErrorKind::Tool => TISSUE_INVALID_ARGUMENT,
        SceneErrorKind::Simulation => TISSUE_SIMULATION,
    }
}

impl From<SceneError> for Error {
    fn from(e: SceneError) -> Self {
        Error::new(status_of(e.kind()), e.to_string())
    }
}

impl From<&tissue_meshio::MeshIoError> for Error {
    fn from(e: &tissue_meshio::MeshIoError) -> Self {
        Error::new(status_of(SceneErrorKind::of_mesh_io(e)), e.to_string())
    }
}

impl From<tissue_pbd::PbdError> for Error {
    fn from(e: tissue_pbd::PbdError) -> Self {
        Error::from(SceneError::from(e))
    }
}

thread_local! {
    /// The message of the last failed call on this thread (empty: none).
    static LAST_ERROR: RefCell<String> = const { RefCell::new(String::new()) };
}

fn set_last_error(message: String) {
    tracing::debug!(message = %message, "tissue C API call failed");
    LAST_ERROR.with(|e| *e.borrow_mut() = message);
}

fn clear_last_error() {
    LAST_ERROR.with(|e| e.borrow_mut().clear());
}

/// The text of a panic's payload.
fn panic_text(payload: &(dyn Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_owned()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic without a message".to_owned()
    }
}

/// Runs one entry point's body: clears this thread's last error, catches a panic
/// (`TISSUE_PANIC`), and turns an error into its status with the message kept for
/// `tissue_last_error`.
pub(crate) fn guard(body: impl FnOnce() -> Result<(), Error>) -> tissue_status {
    clear_last_error();
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(())) => TISSUE_OK,
        Ok(Err(e)) => {
            set_last_error(e.message);
            e.status
        }
        Err(payload) => {
            set_last_error(format!(
                "the tissue library panicked (a bug, please report it): {}; the panic was \
                 caught, but the handle involved may be inconsistent: free it",
                panic_text(payload.as_ref())
            ));
            TISSUE_PANIC
        }
    }
}

/// Runs a `void` entry point's body (a `_free`), swallowing a panic.
pub(crate) fn guard_void(body: impl FnOnce()) {
    let _ = catch_unwind(AssertUnwindSafe(body));
}

/// `&*p`, or `TISSUE_NULL_ARGUMENT` naming the argument.
///
/// # Safety
/// `p` is NULL or points to a live `T` for `'a`.
pub(crate) unsafe fn get<'a, T>(p: *const T, name: &str) -> Result<&'a T, Error> {
    // SAFETY: the caller's contract.
    unsafe { p.as_ref() }.ok_or_else(|| Error::null(name))
}

/// Writes `value` to `*p`, or `TISSUE_NULL_ARGUMENT`.
///
/// # Safety
/// `p` is NULL or valid for a write of a `T`.
pub(crate) unsafe fn put<T>(p: *mut T, name: &str, value: T) -> Result<(), Error> {
    if p.is_null() {
        return Err(Error::null(name));
    }
    // SAFETY: not NULL, and valid by the caller's contract; `write` does not read the old value.
    unsafe { p.write(value) };
    Ok(())
}

/// Writes `value` to `*p` when `p` is not NULL (an optional output).
///
/// # Safety
/// As [`put`].
pub(crate) unsafe fn put_opt<T>(p: *mut T, value: T) {
    if !p.is_null() {
        // SAFETY: the caller's contract.
        unsafe { p.write(value) };
    }
}

/// The `len` elements at `p` (NULL allowed when `len` is 0).
///
/// # Safety
/// `p` is NULL or valid for reads of `len` elements for `'a`.
pub(crate) unsafe fn slice<'a, T>(p: *const T, len: usize, name: &str) -> Result<&'a [T], Error> {
    if len == 0 {
        return Ok(&[]);
    }
    if p.is_null() {
        return Err(Error::null(name));
    }
    // SAFETY: the caller's contract.
    Ok(unsafe { std::slice::from_raw_parts(p, len) })
}

/// Three floats at `p`, as a vector.
///
/// # Safety
/// `p` is NULL or valid for reads of 3 floats.
pub(crate) unsafe fn vec3(p: *const f32, name: &str) -> Result<glam::Vec3, Error> {
    // SAFETY: the caller's contract.
    let s = unsafe { slice(p, 3, name) }?;
    let v = glam::Vec3::new(s[0], s[1], s[2]);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::invalid(format!(
            "`{name}` must be 3 finite numbers, got {v}"
        )))
    }
}

/// Copies `data` into the caller's buffer of `capacity` elements, refusing a buffer that is too
/// small (`TISSUE_BUFFER_TOO_SMALL`, saying how large it must be).
///
/// # Safety
/// `out` is NULL or valid for writes of `capacity` elements.
pub(crate) unsafe fn copy_out<T: Copy>(
    out: *mut T,
    capacity: usize,
    data: &[T],
    what: &str,
) -> Result<(), Error> {
    if capacity < data.len() {
        return Err(Error::new(
            TISSUE_BUFFER_TOO_SMALL,
            format!(
                "the buffer for {what} holds {capacity} elements, {} are needed: query the size \
                 first",
                data.len()
            ),
        ));
    }
    if data.is_empty() {
        return Ok(());
    }
    if out.is_null() {
        return Err(Error::null(what));
    }
    // SAFETY: `out` holds at least `data.len()` elements by the caller's contract; a Rust slice
    // and a caller's buffer do not overlap.
    unsafe { std::ptr::copy_nonoverlapping(data.as_ptr(), out, data.len()) };
    Ok(())
}

/// Copies `text` with a NUL into the caller's buffer: `*length` (if not NULL) is always set to
/// the bytes needed, NUL included; a NULL or short buffer is `TISSUE_BUFFER_TOO_SMALL`.
///
/// # Safety
/// `out` is NULL or valid for writes of `capacity` bytes; `length` is NULL or valid.
pub(crate) unsafe fn copy_text(
    out: *mut c_char,
    capacity: usize,
    length: *mut usize,
    text: &str,
    what: &str,
) -> Result<(), Error> {
    let needed = text.len() + 1;
    // SAFETY: the caller's contract.
    unsafe { put_opt(length, needed) };
    if out.is_null() || capacity < needed {
        return Err(Error::new(
            TISSUE_BUFFER_TOO_SMALL,
            format!(
                "{what} needs a buffer of {needed} bytes (NUL included), got {}: query the \
                 length first",
                if out.is_null() { 0 } else { capacity }
            ),
        ));
    }
    // SAFETY: `out` holds at least `needed` bytes.
    unsafe {
        std::ptr::copy_nonoverlapping(text.as_ptr().cast::<c_char>(), out, text.len());
        out.add(text.len()).write(0);
    }
    Ok(())
}

/// The UTF-8 text at `p`.
///
/// # Safety
/// `p` is NULL or a NUL-terminated string alive for `'a`.
pub(crate) unsafe fn text<'a>(p: *const c_char, name: &str) -> Result<&'a str, Error> {
    if p.is_null() {
        return Err(Error::null(name));
    }
    // SAFETY: the caller's contract.
    unsafe { CStr::from_ptr(p) }
        .to_str()
        .map_err(|e| Error::invalid(format!("`{name}` is not UTF-8: {e}")))
}

/// A new handle owned by the caller.
pub(crate) fn into_handle<T>(value: T) -> *mut T {
    Box::into_raw(Box::new(value))
}

/// Frees a handle made by [`into_handle`] (NULL: nothing).
///
/// # Safety
/// `p` is NULL or came from [`into_handle`] and was not freed.
pub(crate) unsafe fn free_handle<T>(p: *mut T) {
    if !p.is_null() {
        // SAFETY: the caller's contract.
        drop(unsafe { Box::from_raw(p) });
    }
}

/// A poisoned lock: a panic happened while it was held.
pub(crate) fn poisoned<T>(_: T) -> Error {
    Error::new(
        TISSUE_PANIC,
        "an earlier call panicked while it held this handle: free it",
    )
}

/// Copies this thread's last error message into `buffer` (`capacity` bytes, NUL included,
/// truncated to fit) and returns the size a buffer needs for all of it: the message's length in
/// bytes plus 1, or 0 when the last call on this thread succeeded. Call it with `NULL, 0` to
/// query the size. The message is UTF-8, one line, and names what to change.
///
/// Every fallible call clears the message when it starts and sets it when it fails.
///
/// Thread safety: any thread; the message is this thread's own.
#[no_mangle]
pub extern "C" fn tissue_last_error(buffer: *mut c_char, capacity: usize) -> usize {
    catch_unwind(AssertUnwindSafe(|| {
        LAST_ERROR.with(|e| {
            let e = e.borrow();
            if e.is_empty() {
                if !buffer.is_null() && capacity > 0 {
                    // SAFETY: `buffer` holds at least one byte.
                    unsafe { buffer.write(0) };
                }
                return 0;
            }
            if !buffer.is_null() && capacity > 0 {
                let mut n = e.len().min(capacity - 1);
                while !e.is_char_boundary(n) {
                    n -= 1;
                }
                // SAFETY: `buffer` holds `capacity` > n bytes by the caller's contract.
                unsafe {
                    std::ptr::copy_nonoverlapping(e.as_ptr().cast::<c_char>(), buffer, n);
                    buffer.add(n).write(0);
                }
            }
            e.len() + 1
        })
    }))
    .unwrap_or(0)
}

/// The library's version, e.g. `"0.1.0"` (a static string: do not free it).
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_version() -> *const c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}

/// Panics inside the library on purpose and returns `TISSUE_PANIC` with the panic's message in
/// `tissue_last_error`: for hosts (and this library's tests) to check that a panic is caught and
/// reported, never unwound into C. Touches no state.
///
/// Thread safety: any thread.
#[no_mangle]
pub extern "C" fn tissue_debug_panic() -> tissue_status {
    guard(|| {
        #[allow(clippy::panic)]
        if !std::hint::black_box(false) {
            panic!("tissue_debug_panic was called: a test of the panic guard");
        }
        Ok(())
    })
}
