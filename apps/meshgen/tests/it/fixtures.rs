//! Every generated fixture is exactly what `fixtures/generate.sh` makes: each `gen …` line of the
//! script is run through the real `meshgen` binary into a temporary folder and the bytes are
//! compared with the committed file.
#![allow(clippy::unwrap_used)]

use std::path::{Path, PathBuf};
use std::process::Command;

fn fixtures() -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures")).to_path_buf()
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("tissue-meshgen-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn fixtures_match_generator() {
    let script = std::fs::read_to_string(fixtures().join("generate.sh")).unwrap();
    let out_dir = scratch("fixtures");
    let mut checked = 0;
    for line in script.lines().filter(|l| l.starts_with("gen ")) {
        let mut args: Vec<&str> = line.split_whitespace().skip(1).collect();
        let file = args.pop().unwrap();
        let out = out_dir.join(file);
        let status = Command::new(env!("CARGO_BIN_EXE_meshgen"))
            .args(&args)
            .arg(&out)
            .status()
            .unwrap();
        assert!(status.success(), "meshgen failed on: {line}");
        let made = std::fs::read(&out).unwrap();
        let committed = std::fs::read(fixtures().join(file))
            .unwrap_or_else(|e| panic!("fixture {file} missing ({e}); run fixtures/generate.sh"));
        assert!(
            made == committed,
            "fixtures/{file} differs from `meshgen {}`: run fixtures/generate.sh",
            args.join(" ")
        );
        checked += 1;
    }
    assert_eq!(checked, 6, "generate.sh should make six fixtures");
    std::fs::remove_dir_all(&out_dir).ok();
}

#[test]
fn bad_parameters_exit_with_the_shared_codes_and_a_message() {
    use tissue_cli::Exit;
    let out_dir = scratch("bad");
    let out = Command::new(env!("CARGO_BIN_EXE_meshgen"))
        .args(["grid", "--n", "1", "--side", "1"])
        .arg(out_dir.join("x.obj"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(Exit::Parameters.code().into()));
    assert!(String::from_utf8_lossy(&out.stderr).contains("meshgen:"));
    assert!(!out_dir.join("x.obj").exists());

    let out = Command::new(env!("CARGO_BIN_EXE_meshgen"))
        .args(["cube", "--per-edge", "2", "--side", "1"])
        .arg(out_dir.join("x.xyz"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(Exit::Usage.code().into()));
    assert!(String::from_utf8_lossy(&out.stderr).contains("x.xyz"));
    std::fs::remove_dir_all(&out_dir).ok();
}
