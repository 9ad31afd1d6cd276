//! A private temporary folder (mode 0700), removed with everything in it when dropped: where
//! meshes are written through tissue-meshio (which writes to paths) to be read back as bytes.

use std::fs::DirBuilder;
use std::io;
use std::path::{Path, PathBuf};

/// A temporary folder, removed on drop.
#[derive(Debug)]
pub(crate) struct TempDir(PathBuf);

impl TempDir {
    /// A new folder `.tissue-cases-<random>` in `parent`.
    pub(crate) fn new_in(parent: &Path) -> io::Result<TempDir> {
        let mut bits = [0u8; 12];
        getrandom::fill(&mut bits)
            .map_err(|e| io::Error::other(format!("no random name for a temporary folder: {e}")))?;
        let path = parent.join(format!(".tissue-cases-{}", crate::blob::hex(&bits)));
        let mut builder = DirBuilder::new();
        #[cfg(unix)]
        {
            use std::os::unix::fs::DirBuilderExt;
            builder.mode(0o700);
        }
        builder.create(&path)?;
        Ok(TempDir(path))
    }

    /// Its path.
    pub(crate) fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        // Best effort: a leftover folder in the temporary area is not worth failing over.
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Removes the `.tissue-cases-*` folders in `parent` last changed more than `older_than` ago:
/// what an export killed mid-way left behind (they hold a patient's meshes). Best effort; a
/// younger one may belong to an export running in another process and is left.
pub(crate) fn sweep_stale(parent: &Path, older_than: std::time::Duration) {
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        if !name.to_string_lossy().starts_with(".tissue-cases-") {
            continue;
        }
        let stale = entry
            .metadata()
            .and_then(|m| m.modified())
            .ok()
            .and_then(|t| t.elapsed().ok())
            .is_some_and(|age| age > older_than);
        if stale && entry.file_type().is_ok_and(|t| t.is_dir()) {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_stale_export_folders_are_swept() {
        let parent = std::env::temp_dir().join(format!("tissue-sweep-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&parent);
        std::fs::create_dir_all(&parent).unwrap();
        let left = TempDir::new_in(&parent).unwrap();
        let leftover = left.path().to_path_buf();
        std::mem::forget(left); // as a killed export leaves it
        std::fs::write(leftover.join("patient.ply"), b"ply").unwrap();
        std::fs::create_dir(parent.join("keep")).unwrap();
        sweep_stale(&parent, std::time::Duration::from_secs(3600));
        assert!(leftover.exists(), "a young folder may be another export's");
        sweep_stale(&parent, std::time::Duration::ZERO);
        assert!(!leftover.exists(), "a stale export folder is removed");
        assert!(parent.join("keep").exists(), "other folders are left");
        std::fs::remove_dir_all(&parent).unwrap();
    }
}
