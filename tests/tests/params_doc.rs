//! The params tables of the docs are the code's: every process binary of the workspace prints
//! its params (`PROGRAM --describe-params`), `caravan docs params --check` regenerates each
//! table between `<!-- params:PROGRAM -->` and `<!-- /params -->` and fails naming the process
//! and the key a page lacks or has wrong; and every process binary has such a table on some
//! page (docs/**/*.md, launch/**/README.md), so a new process cannot go undocumented.

use serde_json::Value;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Binaries that are command-line tools, not processes of a group: they take arguments, not
/// a launch file's `params`, so they have no params table.
const TOOLS: &[&str] = &[
    "caravan",                     // the launcher and its commands
    "caravan-convoy-bench",        // benchmarks, clap arguments
    "caravan-contact-table",       // Table 1 by Monte-Carlo, clap arguments
    "caravan-contact-urdf",        // prints the arm's URDF
    "caravan-tracked-terrain",     // terrain generator, clap arguments
    "caravan-tracked-urdf",        // URDF generator, clap arguments
    "caravan-tracked-passability", // a sweep's table, clap arguments
    "caravan-uav-curve",           // learning curves, clap arguments
    "caravan-imu-allan",           // the Allan-deviation run, clap arguments
];

/// Packages whose binaries exist only for the tests (a test node, a test report plugin).
const TEST_PACKAGES: &[&str] = &["caravan-tests"];

/// Every binary target of the workspace's packages, by `cargo metadata`.
fn workspace_binaries(root: &Path) -> BTreeSet<String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--offline",
            "--no-deps",
        ])
        .current_dir(root)
        .output()
        .expect("cannot run cargo metadata");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: Value = serde_json::from_slice(&out.stdout).expect("cargo metadata prints JSON");
    let mut bins = BTreeSet::new();
    for package in meta["packages"].as_array().unwrap() {
        if TEST_PACKAGES.contains(&package["name"].as_str().unwrap_or("")) {
            continue;
        }
        for target in package["targets"].as_array().unwrap() {
            let is_bin = target["kind"]
                .as_array()
                .is_some_and(|k| k.iter().any(|k| k == "bin"));
            if is_bin {
                bins.insert(target["name"].as_str().unwrap().to_string());
            }
        }
    }
    bins
}

/// The programs whose params tables the pages ask for, from their `<!-- params:… -->` markers.
fn documented(root: &Path) -> BTreeSet<String> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).into_iter().flatten().flatten() {
            let path = entry.path();
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "md") {
                out.push(path);
            }
        }
    }
    let mut pages = Vec::new();
    walk(&root.join("docs"), &mut pages);
    let mut launch = Vec::new();
    walk(&root.join("launch"), &mut launch);
    pages.extend(
        launch
            .into_iter()
            .filter(|p| p.file_name().is_some_and(|n| n == "README.md")),
    );
    let mut out = BTreeSet::new();
    for page in pages {
        let text = std::fs::read_to_string(&page).unwrap();
        for part in text.split("<!-- params:").skip(1) {
            if let Some((name, _)) = part.split_once("-->") {
                out.extend(name.split_whitespace().map(str::to_string));
            }
        }
    }
    out
}

#[test]
fn every_process_binary_has_a_params_table() {
    let root = caravan_tests::workspace_root();
    let documented = documented(&root);
    let missing: Vec<_> = workspace_binaries(&root)
        .into_iter()
        .filter(|b| !TOOLS.contains(&b.as_str()) && !documented.contains(b))
        .collect();
    assert!(
        missing.is_empty(),
        "process binaries without a params table: {missing:?}; give each a \
         `<!-- params:NAME -->` `<!-- /params -->` pair on its page (docs/processes.md, or the \
         scenario's docs/<scenario>.md) and run `caravan docs params`, or list a command-line \
         tool in TOOLS"
    );
    let stale: Vec<_> = TOOLS
        .iter()
        .filter(|t| !workspace_binaries(&root).contains(**t))
        .collect();
    assert!(
        stale.is_empty(),
        "TOOLS names binaries that no longer exist: {stale:?}"
    );
}

#[test]
fn params_tables_match_the_code() {
    let root = caravan_tests::workspace_root();
    let caravan = caravan_tests::workspace_bin("caravan");
    let out = Command::new(&caravan)
        .args(["docs", "params", "--check", "--root"])
        .arg(&root)
        .output()
        .expect("cannot run caravan docs params");
    assert!(
        out.status.success(),
        "the params tables differ from the code (run `caravan docs params` to rewrite them):\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
