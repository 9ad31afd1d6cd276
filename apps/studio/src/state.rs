//! What the server holds: the patients loaded, the finished jobs, the running job, and its
//! temporary folder.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use tissue_planner::Patient;
use tokio::sync::watch;

/// Largest upload, bytes (64 MiB: a 160k-triangle scan as text OBJ is about 10 MiB).
pub const UPLOAD_LIMIT: usize = 64 * 1024 * 1024;

/// How many patients and how many finished jobs are kept (oldest dropped first).
pub const KEPT: usize = 8;

/// A job that finished: its folder of downloads.
#[derive(Debug)]
pub struct Finished {
    /// The job's id.
    pub id: String,
    /// Its folder in the temporary folder.
    pub dir: PathBuf,
}

/// The running job: its id, its cancel flag, and how far it is.
#[derive(Debug, Clone)]
pub struct Running {
    /// The job's id.
    pub id: String,
    /// Set to cancel it.
    pub cancel: Arc<AtomicBool>,
}

#[derive(Debug, Default)]
struct Inner {
    patients: VecDeque<(String, Arc<Patient>)>,
    finished: VecDeque<Finished>,
    running: Option<Running>,
}

/// The server's state, shared by every request (cheap to clone).
#[derive(Debug, Clone)]
pub struct Studio {
    organs: Arc<crate::trainer::Organs>,
    inner: Arc<Mutex<Inner>>,
    next: Arc<AtomicU64>,
    temp: Arc<PathBuf>,
    shutdown: watch::Sender<bool>,
}

impl Studio {
    /// A studio with a new temporary folder.
    ///
    /// # Errors
    /// The folder cannot be made.
    pub fn new() -> std::io::Result<Studio> {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.subsec_nanos());
        let temp =
            std::env::temp_dir().join(format!("tissue-studio-{}-{nanos:09}", std::process::id()));
        std::fs::create_dir_all(&temp)?;
        let (shutdown, _) = watch::channel(false);
        Ok(Studio {
            organs: Arc::default(),
            inner: Arc::default(),
            next: Arc::new(AtomicU64::new(1)),
            temp: Arc::new(temp),
            shutdown,
        })
    }

    fn lock(&self) -> MutexGuard<'_, Inner> {
        // A panic while holding the lock cannot leave the lists inconsistent (each change is
        // one push or pop), so a poisoned lock is taken as it is.
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The trainer's organs (uploads) and its one-session flag.
    pub fn organs(&self) -> Arc<crate::trainer::Organs> {
        Arc::clone(&self.organs)
    }

    /// A new id with `prefix` (`p1`, `j2`, …).
    pub fn id(&self, prefix: &str) -> String {
        format!("{prefix}{}", self.next.fetch_add(1, Ordering::Relaxed))
    }

    /// The temporary folder: everything the server writes is in it.
    pub fn temp_dir(&self) -> &Path {
        &self.temp
    }

    /// Keeps `patient` under a new id.
    pub fn add_patient(&self, patient: Patient) -> String {
        let id = self.id("p");
        let mut inner = self.lock();
        inner.patients.push_back((id.clone(), Arc::new(patient)));
        while inner.patients.len() > KEPT {
            inner.patients.pop_front();
        }
        id
    }

    /// The patient `id`.
    pub fn patient(&self, id: &str) -> Option<Arc<Patient>> {
        self.lock()
            .patients
            .iter()
            .find(|(i, _)| i == id)
            .map(|(_, p)| Arc::clone(p))
    }

    /// Marks a job running, unless one is: then `Err` with the running one's id.
    pub fn start_job(&self, id: &str) -> Result<Running, String> {
        let mut inner = self.lock();
        if let Some(r) = &inner.running {
            return Err(r.id.clone());
        }
        let running = Running {
            id: id.to_owned(),
            cancel: Arc::new(AtomicBool::new(false)),
        };
        inner.running = Some(running.clone());
        Ok(running)
    }

    /// Marks job `id` ended.
    pub fn end_job(&self, id: &str) {
        let mut inner = self.lock();
        if inner.running.as_ref().is_some_and(|r| r.id == id) {
            inner.running = None;
        }
    }

    /// Whether a job runs now.
    pub fn is_busy(&self) -> bool {
        self.lock().running.is_some()
    }

    /// A folder for job `id`'s files.
    ///
    /// # Errors
    /// It cannot be made.
    pub fn job_dir(&self, id: &str) -> std::io::Result<PathBuf> {
        let dir = self.temp.join(id);
        std::fs::create_dir_all(&dir)?;
        Ok(dir)
    }

    /// Keeps job `id`'s folder for downloads, dropping the oldest beyond [`KEPT`].
    pub fn add_finished(&self, id: &str, dir: PathBuf) {
        let mut inner = self.lock();
        inner.finished.push_back(Finished {
            id: id.to_owned(),
            dir,
        });
        while inner.finished.len() > KEPT {
            if let Some(old) = inner.finished.pop_front() {
                let _ = std::fs::remove_dir_all(&old.dir);
            }
        }
    }

    /// The folder of finished job `id`.
    pub fn finished_dir(&self, id: &str) -> Option<PathBuf> {
        self.lock()
            .finished
            .iter()
            .find(|f| f.id == id)
            .map(|f| f.dir.clone())
    }

    /// A receiver that changes to `true` when the server stops.
    pub fn on_shutdown(&self) -> watch::Receiver<bool> {
        self.shutdown.subscribe()
    }

    /// Stops: cancels the running job, tells every socket to close, and removes the temporary
    /// folder.
    pub fn shutdown(&self) {
        if let Some(r) = &self.lock().running {
            r.cancel.store(true, Ordering::Relaxed);
        }
        self.shutdown.send_replace(true);
        let _ = std::fs::remove_dir_all(self.temp.as_path());
    }
}
