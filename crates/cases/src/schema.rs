//! Opening the database: the folder and file with their modes, the connection's pragmas, and the
//! migrations by `PRAGMA user_version`.

use std::fs::{DirBuilder, OpenOptions};
use std::path::Path;
use std::time::Duration;

use rusqlite::{Connection, TransactionBehavior};

use crate::{CaseError, SCHEMA_VERSION};

/// The migrations in order: entry `i` takes the schema from version `i` to `i + 1`, in one
/// transaction. Never edit an entry once released: add one.
pub const MIGRATIONS: &[&str] = &[
    // 1: patients, plans, content-addressed blobs.
    "CREATE TABLE blobs (
        hash TEXT PRIMARY KEY NOT NULL,
        size INTEGER NOT NULL,
        bytes BLOB NOT NULL
    );
    CREATE TABLE patients (
        id INTEGER PRIMARY KEY,
        uid TEXT NOT NULL UNIQUE,
        label TEXT NOT NULL,
        unit TEXT NOT NULL,
        scan_name TEXT NOT NULL,
        scan_sha256 TEXT NOT NULL,
        scan_blob TEXT NOT NULL REFERENCES blobs(hash),
        mesh_blob TEXT NOT NULL REFERENCES blobs(hash),
        summary TEXT NOT NULL,
        added_at TEXT NOT NULL,
        UNIQUE (scan_sha256, unit)
    );
    CREATE TABLE plans (
        id INTEGER PRIMARY KEY,
        uid TEXT NOT NULL UNIQUE,
        patient_id INTEGER NOT NULL REFERENCES patients(id) ON DELETE CASCADE,
        name TEXT NOT NULL,
        note TEXT NOT NULL,
        mode TEXT NOT NULL,
        tool TEXT NOT NULL,
        solver TEXT NOT NULL,
        library_version TEXT NOT NULL,
        run_at TEXT NOT NULL,
        job TEXT NOT NULL,
        report TEXT NOT NULL,
        area_gain_cm2 REAL,
        volume_cm3 REAL,
        result_blob TEXT REFERENCES blobs(hash),
        chart_blob TEXT REFERENCES blobs(hash)
    );
    CREATE INDEX plans_by_patient ON plans (patient_id, run_at);",
];

/// The database error of `doing`.
pub(crate) fn db(doing: &'static str) -> impl Fn(rusqlite::Error) -> CaseError {
    move |source| CaseError::Database { doing, source }
}

/// Makes `dir` (0700 on unix; an existing folder keeps its mode) and the database file (0600,
/// before SQLite opens it), opens it, refuses a newer schema untouched, sets the pragmas and
/// migrates.
pub(crate) fn open(dir: &Path) -> Result<Connection, CaseError> {
    let open_err = |path: &Path| {
        let path = path.to_path_buf();
        move |source| CaseError::Open { path, source }
    };
    let mut builder = DirBuilder::new();
    builder.recursive(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::DirBuilderExt;
        builder.mode(0o700);
    }
    builder.create(dir).map_err(open_err(dir))?;
    let path = dir.join(crate::DATABASE_FILE);
    let mut options = OpenOptions::new();
    options.read(true).write(true).create(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.mode(0o600);
    }
    drop(options.open(&path).map_err(open_err(&path))?);

    let conn = Connection::open(&path).map_err(db("opening the database"))?;
    conn.busy_timeout(Duration::from_secs(10))
        .map_err(db("setting the busy timeout"))?;
    // Read the version before anything writes: a newer database is left exactly as it is.
    let found = user_version(&conn)?;
    if found > SCHEMA_VERSION {
        return Err(CaseError::Newer {
            path,
            found,
            supported: SCHEMA_VERSION,
        });
    }
    let mode: String = conn
        .pragma_update_and_check(None, "journal_mode", "WAL", |row| row.get(0))
        .map_err(db("turning on the write-ahead log"))?;
    if !mode.eq_ignore_ascii_case("wal") {
        return Err(CaseError::Open {
            path,
            source: std::io::Error::other(format!(
                "the database would not switch to WAL mode (it is in {mode} mode); put the library on a local disk"
            )),
        });
    }
    conn.execute_batch(
        "PRAGMA synchronous = FULL; PRAGMA foreign_keys = ON; PRAGMA secure_delete = ON;",
    )
    .map_err(db("setting the database's pragmas"))?;
    migrate(&conn, &path)?;
    Ok(conn)
}

/// `PRAGMA user_version`.
pub(crate) fn user_version(conn: &Connection) -> Result<u32, CaseError> {
    let v: i64 = conn
        .pragma_query_value(None, "user_version", |row| row.get(0))
        .map_err(db("reading the schema version"))?;
    Ok(u32::try_from(v).unwrap_or(u32::MAX))
}

/// Applies the migrations past the database's version, each in its own `BEGIN IMMEDIATE`
/// transaction that re-reads the version (another process may have migrated meanwhile).
fn migrate(conn: &Connection, path: &Path) -> Result<(), CaseError> {
    let _span = tracing::info_span!("cases_migrate").entered();
    for (i, sql) in MIGRATIONS.iter().enumerate() {
        let to = i as u32 + 1;
        if user_version(conn)? >= to {
            continue;
        }
        // `unchecked_transaction` because the connection is shared by reference here.
        let tx = rusqlite::Transaction::new_unchecked(conn, TransactionBehavior::Immediate)
            .map_err(db("starting a migration"))?;
        let now = user_version(&tx)?;
        if now > SCHEMA_VERSION {
            return Err(CaseError::Newer {
                path: path.to_path_buf(),
                found: now,
                supported: SCHEMA_VERSION,
            });
        }
        if now < to {
            tx.execute_batch(sql).map_err(db("migrating the schema"))?;
            tx.pragma_update(None, "user_version", to)
                .map_err(db("migrating the schema"))?;
        }
        tx.commit().map_err(db("migrating the schema"))?;
    }
    Ok(())
}
