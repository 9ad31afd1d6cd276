//! The golden reports: `insert --job` on each golden job writes the golden report (volatile
//! fields masked), as the studio and the C ABI do for the same job; and the flags that make
//! Table 2 (none) write the same report as its job.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::path::PathBuf;
use std::process::Command;

use tissue_planner::golden;

/// A temporary folder, removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!(
            "tissue-insert-golden-{}-{name}",
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn insert(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_insert"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn every_golden_job_gives_the_golden_report() {
    let scratch = Scratch::new("jobs");
    for name in golden::JOBS {
        let (job, _) = golden::job(name).unwrap();
        let report = scratch.0.join(format!("{name}.json"));
        let out = insert(&[
            "-q",
            "--job",
            job.to_str().unwrap(),
            "--report",
            report.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = std::fs::read_to_string(&report).unwrap();
        if let Err(e) = golden::check(name, &text) {
            panic!("{e}");
        }
    }
}

#[test]
fn the_flags_and_the_job_file_of_table2_write_the_same_report() {
    let scratch = Scratch::new("flags");
    let by_flags = scratch.0.join("flags.json");
    let out = insert(&["-q", "--report", by_flags.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    golden::check("single", &std::fs::read_to_string(&by_flags).unwrap()).unwrap();

    // A job file with request flags beside it is refused: the job is the whole request.
    let (job, _) = golden::job("single").unwrap();
    let out = insert(&["--job", job.to_str().unwrap(), "--volume", "50"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--job takes the whole job"));
}
