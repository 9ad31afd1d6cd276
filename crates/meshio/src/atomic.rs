//! All file access of the crate: whole-file reads, and atomic writes.
//!
//! A write goes to a temporary file `.NAME.tmp-PID-N` in the target's own folder (so the final
//! rename stays on one file system), is flushed and synced, and is then renamed over the target.
//! On any error the temporary file is removed, so a reader of `NAME` sees the old file whole or
//! the new file whole, never a half-written one, and no debris is left behind.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::MeshIoError;

/// Distinguishes temporary files of concurrent writes from one process.
static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Reads a whole file.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, MeshIoError> {
    fs::read(path).map_err(|e| MeshIoError::io(path, e))
}

/// Writes `path` atomically with the bytes that `write` produces.
///
/// Check everything that can be checked before calling this: an error from `write` is reported
/// as [`MeshIoError::Io`] of `path`.
pub(crate) fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> Result<(), MeshIoError> {
    let _span = tracing::debug_span!("write_atomic", path = %path.display()).entered();
    let io_err = |e| MeshIoError::io(path, e);
    let name = path.file_name().ok_or_else(|| {
        io_err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "not a file path (it has no file name)",
        ))
    })?;
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let tmp = dir.join(format!(
        ".{}.tmp-{}-{}",
        name.to_string_lossy(),
        std::process::id(),
        TEMP_COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let file = OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)
        .map_err(io_err)?;
    // From here on the guard removes the temporary file unless the rename succeeded.
    let mut guard = TempGuard {
        path: Some(tmp.clone()),
    };
    let mut out = BufWriter::with_capacity(1 << 16, file);
    write(&mut out).map_err(io_err)?;
    let file = out.into_inner().map_err(|e| io_err(e.into_error()))?;
    file.sync_all().map_err(io_err)?;
    drop(file);
    fs::rename(&tmp, path).map_err(io_err)?;
    guard.path = None;
    // Make the rename itself durable; not every platform can open a folder, so best effort.
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// Writes `bytes` to `path` atomically: a temporary file in the same folder, synced, then
/// renamed over `path`; on any error nothing is left behind.
///
/// # Errors
/// [`MeshIoError::Io`] of `path` when the folder is missing or not writable.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), MeshIoError> {
    use std::io::Write as _;
    write_atomic(path, |out| out.write_all(bytes))
}

/// Removes the temporary file when dropped, unless disarmed by taking `path`.
struct TempGuard {
    path: Option<PathBuf>,
}

impl Drop for TempGuard {
    fn drop(&mut self) {
        if let Some(p) = self.path.take() {
            let _ = fs::remove_file(p);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!(
            "tissue-meshio-atomic-{}-{name}",
            std::process::id()
        ));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn failed_write_leaves_old_file_and_no_temp() {
        let dir = scratch("failed");
        let target = dir.join("a.txt");
        fs::write(&target, b"old").unwrap();
        let err = write_atomic(&target, |w| {
            w.write_all(b"half")?;
            Err(io::Error::other("disk on fire"))
        })
        .unwrap_err();
        assert!(err.to_string().contains("disk on fire"), "{err}");
        assert_eq!(fs::read(&target).unwrap(), b"old");
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 1);
        fs::remove_dir_all(&dir).unwrap();
    }
}
