//! What the server holds: the patients loaded, the finished jobs, the running job, its limits
//! and its temporary folder.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use tissue_planner::{CancelToken, Patient};
use tokio::sync::{watch, OwnedSemaphorePermit, Semaphore};

/// Largest upload, bytes (64 MiB: a 160k-triangle scan as text OBJ is about 10 MiB).
pub const UPLOAD_LIMIT: usize = 64 * 1024 * 1024;

/// Job sockets (planner tabs) open at once; more are refused with 503.
pub const JOB_SOCKETS: usize = 64;

/// How many patients and how many finished jobs are kept (oldest dropped first).
pub const KEPT: usize = 8;

/// The server's limits on time and concurrency (see `serve.rs`); [`Limits::default`] is what
/// `studio` runs with.
#[derive(Debug, Clone)]
pub struct Limits {
    /// A request's headers (and the wait for the next request on a kept-alive connection) must
    /// arrive within this: 30 s.
    pub header_timeout: Duration,
    /// A body that sends no byte for this long is dropped: 30 s.
    pub body_idle: Duration,
    /// A body still unfinished after this long is dropped: 10 min (64 MiB at 110 kB/s).
    pub body_total: Duration,
    /// Uploads read at once (each holds up to [`UPLOAD_LIMIT`] bytes); more are refused with
    /// 503 until one ends: 2.
    pub uploads: usize,
    /// Connections served at once (more wait in the kernel's backlog): 256.
    pub max_connections: usize,
    /// A WebSocket send that the peer does not take within this closes the socket (a tab that
    /// stopped reading): 10 s.
    pub send_timeout: Duration,
    /// After a stop, open connections get this long to finish: 3 s.
    pub shutdown_grace: Duration,
    /// Live previews computed at once on the server, from every tab together (each also has at
    /// most one in flight, the newest): 2, the cores of a small workstation. A tab's preview
    /// waits for a place; a newer one replaces it while it waits.
    pub previews: usize,
}

impl Default for Limits {
    fn default() -> Limits {
        Limits {
            header_timeout: Duration::from_secs(30),
            body_idle: Duration::from_secs(30),
            body_total: Duration::from_secs(600),
            uploads: 2,
            max_connections: 256,
            send_timeout: Duration::from_secs(10),
            shutdown_grace: Duration::from_secs(3),
            previews: 2,
        }
    }
}

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
    /// Cancels it.
    pub cancel: CancelToken,
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
    temp: Arc<PathBuf>,
    shutdown: watch::Sender<bool>,
    limits: Arc<Limits>,
    uploads: Arc<Semaphore>,
    sockets: Arc<Semaphore>,
    previews: Arc<Semaphore>,
}

impl Studio {
    /// A studio with the default [`Limits`] and a new temporary folder.
    ///
    /// # Errors
    /// The folder cannot be made.
    pub fn new() -> std::io::Result<Studio> {
        Studio::with_limits(Limits::default())
    }

    /// A studio with `limits` and a new temporary folder: `$TMPDIR/tissue-studio-RANDOM`, made
    /// afresh (never an existing one) with mode 0700, so other users of the computer cannot list
    /// or read the patients' files in it.
    ///
    /// # Errors
    /// The folder cannot be made.
    pub fn with_limits(limits: Limits) -> std::io::Result<Studio> {
        let name = crate::access::random_hex(12).map_err(std::io::Error::other)?;
        let temp = std::env::temp_dir().join(format!("tissue-studio-{name}"));
        let mut builder = std::fs::DirBuilder::new();
        #[cfg(unix)]
        std::os::unix::fs::DirBuilderExt::mode(&mut builder, 0o700);
        builder.create(&temp)?;
        let (shutdown, _) = watch::channel(false);
        Ok(Studio {
            organs: Arc::default(),
            inner: Arc::default(),
            temp: Arc::new(temp),
            shutdown,
            uploads: Arc::new(Semaphore::new(limits.uploads.max(1))),
            sockets: Arc::new(Semaphore::new(JOB_SOCKETS)),
            previews: Arc::new(Semaphore::new(limits.previews.max(1))),
            limits: Arc::new(limits),
        })
    }

    /// A place for one job socket, or `None` when [`JOB_SOCKETS`] are open.
    pub fn socket_slot(&self) -> Option<OwnedSemaphorePermit> {
        Arc::clone(&self.sockets).try_acquire_owned().ok()
    }

    /// The server-wide places of live previews ([`Limits::previews`]): take one with
    /// `acquire_owned` before computing a preview.
    pub fn preview_slots(&self) -> Arc<Semaphore> {
        Arc::clone(&self.previews)
    }

    /// The limits it runs with.
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// A place for one upload, or `None` when [`Limits::uploads`] are being read.
    pub fn upload_slot(&self) -> Option<OwnedSemaphorePermit> {
        Arc::clone(&self.uploads).try_acquire_owned().ok()
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

    /// A new id: `prefix` and 128 random bits in hex (`p3f…`, `j9c…`), so that an id cannot be
    /// guessed from another (sequential ids let any client enumerate the patients and results).
    pub fn id(&self, prefix: &str) -> String {
        new_id(prefix)
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
            cancel: CancelToken::new(),
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
        std::fs::create_dir(&dir)?;
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
            r.cancel.cancel();
        }
        self.shutdown.send_replace(true);
        let _ = std::fs::remove_dir_all(self.temp.as_path());
    }
}

/// `prefix` and 128 random bits in hex; if the system's generator fails (it does not on the
/// systems we run on), a mix of the clock and a counter, still unique in the process.
pub fn new_id(prefix: &str) -> String {
    match crate::access::random_hex(16) {
        Ok(hex) => format!("{prefix}{hex}"),
        Err(_) => {
            static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
            let nanos = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos());
            format!(
                "{prefix}{nanos:x}{:x}",
                NEXT.fetch_add(1, Ordering::Relaxed)
            )
        }
    }
}
