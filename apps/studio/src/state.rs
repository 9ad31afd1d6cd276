//! What the server holds: the patients loaded (with their scans, for saving), the finished jobs
//! (with what a save needs), the running job, its limits, its temporary folder and the case
//! library.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use tissue_cases::{CaseError, Library, Scan};
use tissue_planner::{CancelToken, JobSpec, Patient};
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

/// A job that finished: its folder of downloads, and what saving it to the case library needs.
#[derive(Debug)]
pub struct Finished {
    /// The job's id.
    pub id: String,
    /// Its folder in the temporary folder.
    pub dir: PathBuf,
    /// What it kept for a save.
    pub kept: Arc<KeptJob>,
}

/// A finished job as the case library stores it: the job as asked, what it finished with, and
/// its patient's scan and label.
#[derive(Debug)]
pub struct KeptJob {
    /// The job as it was asked.
    pub spec: JobSpec,
    /// What it finished with.
    pub finished: tissue_planner::Finished,
    /// The patient it ran on.
    pub patient: Arc<Loaded>,
}

/// A patient the studio holds: ready to plan on, with the scan it came from (what the case
/// library keeps).
#[derive(Debug)]
pub struct Loaded {
    /// Ready to plan on (shared: the previewer keeps it between previews).
    pub patient: Arc<Patient>,
    /// Its scan as it came (an upload's bytes, a shipped mesh written as OBJ, a stored scan).
    pub scan: Scan,
    /// What the case library calls it when a plan on it is saved without a label (an upload's
    /// file name, a shipped mesh's label, a stored patient's label).
    pub label: String,
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
    patients: VecDeque<(String, Arc<Loaded>)>,
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
    library: Arc<Library>,
}

/// The library folder of a studio made without one ([`Studio::with_limits`]): inside its
/// temporary folder, so removed with it.
const TEMPORARY_LIBRARY: &str = "cases";

impl Studio {
    /// A studio with the default [`Limits`], a new temporary folder, and a case library of its
    /// own inside it (removed at shutdown: tests and examples never touch the user's library).
    ///
    /// # Errors
    /// The folder or the library cannot be made.
    pub fn new() -> std::io::Result<Studio> {
        Studio::with_limits(Limits::default())
    }

    /// A studio with `limits`, a new temporary folder, and a case library inside it (removed at
    /// shutdown). `studio` itself uses [`Studio::with_data`].
    ///
    /// # Errors
    /// The folder or the library cannot be made.
    pub fn with_limits(limits: Limits) -> std::io::Result<Studio> {
        let temp = make_temp()?;
        let library = Library::open(&temp.join(TEMPORARY_LIBRARY)).map_err(|e| {
            let _ = std::fs::remove_dir_all(&temp);
            std::io::Error::other(e)
        })?;
        Ok(Studio::assemble(limits, temp, library))
    }

    /// A studio with `limits`, a new temporary folder (transient files only), and the case
    /// library in `data` (made with mode 0700 if missing; the database file 0600): what
    /// `studio --data DIR` runs with.
    ///
    /// # Errors
    /// [`CaseError::Open`] when the temporary folder cannot be made; the library's errors.
    pub fn with_data(limits: Limits, data: &Path) -> Result<Studio, CaseError> {
        let temp = make_temp().map_err(|source| CaseError::Open {
            path: std::env::temp_dir(),
            source,
        })?;
        match Library::open(data) {
            Ok(library) => Ok(Studio::assemble(limits, temp, library)),
            Err(e) => {
                let _ = std::fs::remove_dir_all(&temp);
                Err(e)
            }
        }
    }

    fn assemble(limits: Limits, temp: PathBuf, library: Library) -> Studio {
        let (shutdown, _) = watch::channel(false);
        Studio {
            organs: Arc::default(),
            inner: Arc::default(),
            temp: Arc::new(temp),
            shutdown,
            uploads: Arc::new(Semaphore::new(limits.uploads.max(1))),
            sockets: Arc::new(Semaphore::new(JOB_SOCKETS)),
            previews: Arc::new(Semaphore::new(limits.previews.max(1))),
            limits: Arc::new(limits),
            library: Arc::new(library),
        }
    }

    /// The case library (shared by every request; its calls block, so make them off the async
    /// threads).
    pub fn library(&self) -> &Arc<Library> {
        &self.library
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

    /// Keeps `patient` (with the scan it came from and its label in the case library) under a
    /// new id.
    pub fn add_patient(&self, patient: Patient, scan: Scan, label: String) -> String {
        let id = self.id("p");
        let mut inner = self.lock();
        inner.patients.push_back((
            id.clone(),
            Arc::new(Loaded {
                patient: Arc::new(patient),
                scan,
                label,
            }),
        ));
        while inner.patients.len() > KEPT {
            inner.patients.pop_front();
        }
        id
    }

    /// The patient `id`, with its scan.
    pub fn patient(&self, id: &str) -> Option<Arc<Loaded>> {
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

    /// Keeps job `id`'s folder for downloads and what a save needs, dropping the oldest beyond
    /// [`KEPT`].
    pub fn add_finished(&self, id: &str, dir: PathBuf, kept: KeptJob) {
        let mut inner = self.lock();
        inner.finished.push_back(Finished {
            id: id.to_owned(),
            dir,
            kept: Arc::new(kept),
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

    /// What finished job `id` kept for a save.
    pub fn kept_job(&self, id: &str) -> Option<Arc<KeptJob>> {
        self.lock()
            .finished
            .iter()
            .find(|f| f.id == id)
            .map(|f| Arc::clone(&f.kept))
    }

    /// Forgets the patients whose scan has SHA-256 `sha256` (and `bytes` bytes), and the
    /// finished jobs run on them with their folders: an erased patient leaves the studio too.
    /// Returns how many patients and jobs went.
    pub fn forget_scan(&self, sha256: &str, bytes: u64) -> usize {
        let same = |l: &Loaded| l.scan.bytes.len() as u64 == bytes && l.scan.sha256() == sha256;
        let mut inner = self.lock();
        let before = inner.patients.len() + inner.finished.len();
        inner.patients.retain(|(_, l)| !same(l));
        let mut gone = Vec::new();
        inner.finished.retain(|f| {
            let keep = !same(&f.kept.patient);
            if !keep {
                gone.push(f.dir.clone());
            }
            keep
        });
        let count = before - inner.patients.len() - inner.finished.len();
        drop(inner);
        for dir in gone {
            let _ = std::fs::remove_dir_all(dir);
        }
        count
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

/// A new private temporary folder: `$TMPDIR/tissue-studio-RANDOM`, made afresh (never an
/// existing one) with mode 0700, so other users of the computer cannot list or read the
/// patients' files in it.
fn make_temp() -> std::io::Result<PathBuf> {
    let name = crate::access::random_hex(12).map_err(std::io::Error::other)?;
    let temp = std::env::temp_dir().join(format!("tissue-studio-{name}"));
    let mut builder = std::fs::DirBuilder::new();
    #[cfg(unix)]
    std::os::unix::fs::DirBuilderExt::mode(&mut builder, 0o700);
    builder.create(&temp)?;
    Ok(temp)
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
