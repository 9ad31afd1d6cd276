//! ARCHITECTURE.md's dependency graph is the workspace's: the edges listed in its `deps` block
//! are exactly the normal (not dev, not build) dependencies between the workspace's `tissue-*`
//! packages, as `cargo metadata` reports them. The test names every missing and every extra
//! edge, so the map cannot drift from the manifests.
//!
//! It lives in tissue-cli, the crate every binary shares and that depends on no other tissue
//! crate, so that it runs without building the physics.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::process::Command;

type Graph = BTreeMap<String, BTreeSet<String>>;

fn workspace_root() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

/// `cargo metadata --no-deps` of the workspace.
fn metadata() -> serde_json::Value {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let output = Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--offline",
            "--no-deps",
        ])
        .current_dir(workspace_root())
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "cargo metadata failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).unwrap()
}

/// The normal dependencies between workspace members.
fn cargo_graph() -> Graph {
    let metadata = metadata();
    let mut graph = Graph::new();
    for package in metadata["packages"].as_array().unwrap() {
        let name = package["name"].as_str().unwrap().to_owned();
        let deps = package["dependencies"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|d| d["kind"].is_null()) // normal; "dev" and "build" are left out
            .filter_map(|d| d["name"].as_str())
            .filter(|d| d.starts_with("tissue-"))
            .map(str::to_owned)
            .collect();
        graph.insert(name, deps);
    }
    graph
}

/// The graph written in ARCHITECTURE.md: the lines `a -> b, c` of its first `deps` block
/// (a fence opened with ```` ```deps ````); blank lines and `#` comments are skipped.
fn documented_graph(text: &str) -> Graph {
    const OPEN: &str = "\n```deps\n";
    let start = text.find(OPEN).expect("no ```deps block");
    let body = &text[start + OPEN.len()..];
    let end = body.find("```").expect("the ```deps block is not closed");
    let mut graph = Graph::new();
    for (i, line) in body[..end].lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let (from, to) = line
            .split_once("->")
            .unwrap_or_else(|| panic!("```deps line {}: `{line}` is not `a -> b, c`", i + 1));
        let deps = to
            .split(',')
            .map(str::trim)
            .filter(|d| !d.is_empty())
            .map(str::to_owned)
            .collect();
        let from = from.trim().to_owned();
        assert!(
            graph.insert(from.clone(), deps).is_none(),
            "```deps lists {from} twice"
        );
    }
    graph
}

/// Edges `a -> b` of `graph` that `other` does not have (a package `other` lacks altogether
/// is named once).
fn edges_missing_from(graph: &Graph, other: &Graph) -> Vec<String> {
    let mut out = Vec::new();
    for (from, deps) in graph {
        let Some(theirs) = other.get(from) else {
            out.push(format!("{from} (the whole package)"));
            continue;
        };
        out.extend(deps.difference(theirs).map(|to| format!("{from} -> {to}")));
    }
    out
}

#[test]
fn architecture_graph_matches_cargo_metadata() {
    let text = std::fs::read_to_string(workspace_root().join("ARCHITECTURE.md")).unwrap();
    let documented = documented_graph(&text);
    let actual = cargo_graph();
    let missing = edges_missing_from(&actual, &documented);
    let extra = edges_missing_from(&documented, &actual);
    assert!(
        missing.is_empty() && extra.is_empty(),
        "ARCHITECTURE.md's ```deps block differs from the manifests:\n\
         missing (in a Cargo.toml, not in the map): {missing:?}\n\
         extra (in the map, not in any Cargo.toml): {extra:?}"
    );
}

/// The comparison itself: an edge the map lacks, one it has too many, and a package it leaves
/// out are all named.
#[test]
fn missing_and_extra_edges_are_named() {
    let documented = documented_graph("x\n```deps\na -> b\n# note\nc ->\n```\n");
    let actual = documented_graph("\n```deps\na -> d\nc -> a\ne -> a\n```\n");
    assert_eq!(
        edges_missing_from(&actual, &documented),
        ["a -> d", "c -> a", "e (the whole package)"]
    );
    assert_eq!(edges_missing_from(&documented, &actual), ["a -> b"]);
}

/// Every member inherits the workspace's lints (`[lints] workspace = true`), so the clippy
/// levels set once in the root `Cargo.toml` hold everywhere.
#[test]
fn every_member_inherits_the_workspace_lints() {
    let metadata = metadata();
    let mut without = Vec::new();
    for package in metadata["packages"].as_array().unwrap() {
        let manifest = std::fs::read_to_string(package["manifest_path"].as_str().unwrap()).unwrap();
        let lints = manifest
            .split("\n[")
            .find(|section| section.starts_with("lints]"))
            .unwrap_or_default();
        let inherits = lints
            .lines()
            .any(|l| l.split_whitespace().collect::<String>() == "workspace=true");
        if !inherits {
            without.push(package["name"].as_str().unwrap().to_owned());
        }
    }
    assert!(
        without.is_empty(),
        "without `[lints] workspace = true`: {without:?}"
    );
}
