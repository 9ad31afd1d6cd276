//! The output files: the deformed patient (OBJ, PLY, STL, VTK with fields), the JSON report and
//! the PNG, staged as hidden temporary files beside their targets and renamed into place only
//! once every one of them was written; a failure or Ctrl-C removes the staged files.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use tissue_planner::PatientResult;

use crate::cli::Cli;
use crate::failure::{Exit, Failure};
use crate::progress::Interrupt;

/// Every output path of the command line.
fn targets(cli: &Cli) -> Vec<&Path> {
    cli.out
        .iter()
        .map(PathBuf::as_path)
        .chain(cli.report.as_deref())
        .chain(cli.png.as_deref())
        .collect()
}

/// Refuses, before anything runs, an output whose folder does not exist.
pub fn check_targets(cli: &Cli) -> Result<(), Failure> {
    for path in targets(cli) {
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        if !dir.is_dir() {
            return Err(Failure::new(
                Exit::Output,
                format!(
                    "cannot write {}: the folder {} does not exist; create it or pick another path",
                    path.display(),
                    dir.display()
                ),
            ));
        }
        if path.is_dir() {
            return Err(Failure::new(
                Exit::Output,
                format!(
                    "cannot write {}: it is a folder; give a file name",
                    path.display()
                ),
            ));
        }
    }
    Ok(())
}

/// Output files written to hidden temporary names, waiting to be renamed into place.
#[derive(Debug, Default)]
pub struct Staged {
    files: Vec<(PathBuf, PathBuf)>,
}

impl Staged {
    /// A temporary name beside `target`: `.NAME.insert-PID.EXT` (the extension kept).
    fn stage(&mut self, target: &Path) -> PathBuf {
        let name = target
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "output".to_owned());
        let ext = target
            .extension()
            .map(|e| format!(".{}", e.to_string_lossy()))
            .unwrap_or_default();
        let tmp_name = format!(
            ".{name}.insert-{}-{}{ext}",
            std::process::id(),
            self.files.len()
        );
        let tmp = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.join(tmp_name),
            _ => PathBuf::from(tmp_name),
        };
        self.files.push((tmp.clone(), target.to_path_buf()));
        tmp
    }

    /// Stages `bytes` for `target`.
    pub fn bytes(&mut self, target: &Path, bytes: &[u8], what: &str) -> Result<(), Failure> {
        let tmp = self.stage(target);
        let write = || -> std::io::Result<()> {
            let mut file = File::create(&tmp)?;
            file.write_all(bytes)?;
            file.sync_all()
        };
        write().map_err(|e| Failure::output(what, format!("{}: {e}", target.display())))
    }

    /// Stages the patient after the run for `target`, in the format of its extension (VTK
    /// with the fields).
    pub fn mesh(&mut self, target: &Path, patient: &PatientResult) -> Result<(), Failure> {
        let tmp = self.stage(target);
        patient
            .write_mesh(&tmp)
            .map_err(|e| Failure::output("mesh", format!("{} ({e})", target.display())))
    }

    /// Renames every staged file into place, unless Ctrl-C was pressed.
    pub fn commit(mut self, interrupt: &Interrupt) -> Result<Vec<PathBuf>, Failure> {
        interrupt.check()?;
        let mut done = Vec::new();
        for (tmp, target) in std::mem::take(&mut self.files) {
            if let Err(e) = std::fs::rename(&tmp, &target) {
                let _ = std::fs::remove_file(&tmp);
                return Err(Failure::output(
                    "output",
                    format!("{}: {e}", target.display()),
                ));
            }
            done.push(target);
        }
        Ok(done)
    }
}

impl Drop for Staged {
    /// Removes what was staged but not committed.
    fn drop(&mut self) {
        for (tmp, _) in &self.files {
            let _ = std::fs::remove_file(tmp);
        }
    }
}
