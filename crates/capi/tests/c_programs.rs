//! Real C99 and C++17 programs against `tissue.h`, compiled with the C and C++ compilers cc-rs
//! finds (`-Wall -Wextra -Werror`), linked against the static library cargo built for this test
//! run (`libtissue.a`, from the crate's `staticlib` type), run, and checked by their exit status.
//! Each program prints its figures; `cargo test -p tissue-capi --release --test c_programs --
//! --nocapture` shows them.
#![allow(clippy::panic, clippy::print_stdout)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// The folder cargo put this run's artefacts in (`target/<profile>`): the test binary is in
/// its `deps`.
fn profile_dir() -> PathBuf {
    let exe = std::env::current_exe().unwrap_or_else(|e| panic!("current_exe: {e}"));
    exe.parent()
        .and_then(Path::parent)
        .map(Path::to_path_buf)
        .unwrap_or_else(|| panic!("{} is not in target/<profile>/deps", exe.display()))
}

/// `libtissue.a`: cargo builds the crate's `staticlib` with the `rlib` this test links (the
/// newer of `target/<profile>/deps` and `target/<profile>`).
fn static_library() -> PathBuf {
    // `cargo build` copies it up to `target/<profile>`; `cargo test` leaves it in `deps`.
    let dir = profile_dir();
    [dir.join("deps/libtissue.a"), dir.join("libtissue.a")]
        .into_iter()
        .filter(|p| p.exists())
        .max_by_key(|p| p.metadata().and_then(|m| m.modified()).ok())
        .unwrap_or_else(|| {
            panic!(
                "libtissue.a is in neither {0}/deps nor {0}: cargo builds it with the test \
                 (crate-type staticlib)",
                dir.display()
            )
        })
}

/// A compiler for C (`cpp = false`) or C++ as cc-rs finds it (honouring `CC`, `CXX`), with
/// our warnings.
fn compiler(cpp: bool) -> Command {
    let target = format!("{}-unknown-linux-gnu", std::env::consts::ARCH);
    let tool = cc::Build::new()
        .cpp(cpp)
        .cargo_metadata(false)
        .cargo_warnings(false)
        .opt_level(1)
        .debug(false)
        .target(&target)
        .host(&target)
        .try_get_compiler()
        .unwrap_or_else(|e| panic!("no C/C++ compiler found by cc-rs: {e}"));
    let mut cmd = tool.to_command();
    let std = if cpp { "-std=c++17" } else { "-std=c99" };
    cmd.args([std, "-Wall", "-Wextra", "-Werror", "-pthread"]);
    cmd
}

/// Compiles `source` (in `tests/c/`) against the header and the static library, runs it with
/// `args`, prints its output and checks that it succeeded.
fn build_and_run(source: &str, args: &[&str]) {
    // One program at a time: the force loop's 1 kHz thread is timed, and the machine may have
    // two cores only.
    static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one = ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let cpp = source.ends_with(".cpp");
    let out_dir = profile_dir().join("capi-tests");
    std::fs::create_dir_all(&out_dir).unwrap_or_else(|e| panic!("{}: {e}", out_dir.display()));
    let exe = out_dir.join(source.replace('.', "_"));
    let mut cmd = compiler(cpp);
    cmd.arg(dir.join("tests/c").join(source))
        .arg("-I")
        .arg(dir.join("include"))
        .arg("-o")
        .arg(&exe)
        .arg(static_library())
        // What Rust's standard library needs from the system (rustc --print native-static-libs).
        .args([
            "-lgcc_s",
            "-lutil",
            "-lrt",
            "-lpthread",
            "-lm",
            "-ldl",
            "-lc",
        ]);
    let built = cmd.output().unwrap_or_else(|e| panic!("{cmd:?}: {e}"));
    assert!(
        built.status.success(),
        "{source} did not compile:\n{}{}",
        String::from_utf8_lossy(&built.stdout),
        String::from_utf8_lossy(&built.stderr)
    );
    let ran = Command::new(&exe)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("{}: {e}", exe.display()));
    let stdout = String::from_utf8_lossy(&ran.stdout);
    let stderr = String::from_utf8_lossy(&ran.stderr);
    println!("---- {source}\n{stdout}{stderr}");
    assert!(
        ran.status.success(),
        "{source} failed ({}):\n{stdout}{stderr}",
        ran.status
    );
}

fn fixture(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures")
        .join(name)
        .display()
        .to_string()
}

#[test]
fn c99_plans_table_2_in_band_reads_the_report_and_reports_errors_and_panics() {
    build_and_run(
        "plan.c",
        &[
            &fixture("plane_20cm_65.obj"),
            &fixture("tets/box_v41_ascii.msh"),
        ],
    );
}

#[test]
fn cpp17_cancels_from_another_thread_sweeps_and_searches() {
    build_and_run("jobs.cpp", &[]);
}

#[test]
fn cpp17_trainer_cuts_sutures_plays_the_demonstration_and_renders_force_at_1khz() {
    build_and_run("trainer.cpp", &[]);
}

#[test]
fn c99_material_twice_the_modulus_sags_half_as_much_and_pushes_back_twice_as_hard() {
    build_and_run("material.c", &[]);
}
