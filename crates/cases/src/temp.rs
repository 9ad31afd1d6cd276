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
