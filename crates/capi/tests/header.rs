//! `include/tissue.h` is what cbindgen makes of the source now: this test regenerates it in
//! memory and fails when the checked-in header differs. `TISSUE_BLESS=1 cargo test -p
//! tissue-capi --test header` writes it instead.

use std::path::Path;

#[test]
fn the_checked_in_header_is_what_cbindgen_makes_of_the_source() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml"))
        .unwrap_or_else(|e| panic!("cbindgen.toml: {e}"));
    let bindings = cbindgen::Builder::new()
        .with_crate(dir)
        .with_config(config)
        .generate()
        .unwrap_or_else(|e| panic!("cbindgen: {e}"));
    let mut fresh = Vec::new();
    bindings.write(&mut fresh);
    let fresh = String::from_utf8(fresh).unwrap_or_default();
    let path = dir.join("include/tissue.h");
    if std::env::var_os("TISSUE_BLESS").is_some_and(|v| v == "1") {
        std::fs::write(&path, &fresh).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        return;
    }
    let checked_in = std::fs::read_to_string(&path).unwrap_or_default();
    if checked_in != fresh {
        let line = checked_in
            .lines()
            .zip(fresh.lines())
            .position(|(a, b)| a != b)
            .map_or_else(
                || "at the end".to_owned(),
                |i| format!("from line {}", i + 1),
            );
        panic!(
            "crates/capi/include/tissue.h is stale (it differs {line}): regenerate it with \
             `TISSUE_BLESS=1 cargo test -p tissue-capi --test header` and commit it"
        );
    }
}
