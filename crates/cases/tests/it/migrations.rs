//! The schema's version, a newer database refused untouched, the files' modes.

use tissue_cases::{CaseError, Library, SCHEMA_VERSION};

use crate::common::{save, table2, table2_single, Tmp};

fn version(path: &std::path::Path) -> i64 {
    rusqlite::Connection::open(path)
        .unwrap()
        .query_row("PRAGMA user_version", [], |r| r.get(0))
        .unwrap()
}

#[test]
fn a_new_library_has_the_schema_version_and_reopening_keeps_it() {
    let tmp = Tmp::new("version");
    let lib = Library::open(&tmp.lib_dir()).unwrap();
    assert_eq!(version(&lib.database_path()), i64::from(SCHEMA_VERSION));
    assert_eq!(tissue_cases::MIGRATIONS.len(), SCHEMA_VERSION as usize);
    let (_, scan) = table2();
    let (spec, finished) = table2_single(100.0, 40);
    let a = save(&lib, &scan, "a", &spec, &finished);
    drop(lib);
    for _ in 0..2 {
        let lib = Library::open(&tmp.lib_dir()).unwrap();
        assert_eq!(version(&lib.database_path()), i64::from(SCHEMA_VERSION));
        assert_eq!(lib.plan(&a.uid).unwrap(), a);
        let mode: String = rusqlite::Connection::open(lib.database_path())
            .unwrap()
            .query_row("PRAGMA journal_mode", [], |r| r.get(0))
            .unwrap();
        assert_eq!(mode, "wal");
    }
}

#[test]
fn a_newer_library_is_refused_and_left_byte_for_byte() {
    let tmp = Tmp::new("newer");
    let dir = tmp.lib_dir();
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(tissue_cases::DATABASE_FILE);
    {
        let conn = rusqlite::Connection::open(&path).unwrap();
        conn.execute_batch(&format!(
            "CREATE TABLE future (x); INSERT INTO future VALUES (1); PRAGMA user_version = {};",
            SCHEMA_VERSION + 1
        ))
        .unwrap();
    }
    let bytes = std::fs::read(&path).unwrap();
    match Library::open(&dir) {
        Err(CaseError::Newer {
            found, supported, ..
        }) => {
            assert_eq!((found, supported), (SCHEMA_VERSION + 1, SCHEMA_VERSION));
        }
        other => panic!("expected Newer, got {other:?}"),
    }
    assert_eq!(std::fs::read(&path).unwrap(), bytes);
    assert!(!dir.join("cases.sqlite-wal").exists());
}

#[cfg(unix)]
#[test]
fn the_folder_is_0700_and_the_database_0600() {
    use std::os::unix::fs::PermissionsExt;
    let tmp = Tmp::new("modes");
    let dir = tmp.0.join("deep").join("library");
    let lib = Library::open(&dir).unwrap();
    let (_, scan) = table2();
    lib.add_patient(&scan, None).unwrap();
    let mode = |p: &std::path::Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode(&dir), 0o700);
    assert_eq!(mode(&lib.database_path()), 0o600);
    assert_eq!(mode(&dir.join("cases.sqlite-wal")), 0o600);
    // An existing folder keeps its mode.
    let shared = tmp.0.join("shared");
    std::fs::create_dir(&shared).unwrap();
    std::fs::set_permissions(&shared, std::fs::Permissions::from_mode(0o750)).unwrap();
    let lib = Library::open(&shared).unwrap();
    assert_eq!(mode(&shared), 0o750);
    assert_eq!(mode(&lib.database_path()), 0o600);
}
