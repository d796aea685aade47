//! The workspace's dependency arrows point down: schemas ← runtime ← launcher (`caravan-cli`);
//! processes and scenarios build on the runtime, never the other way round.

use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::process::Command;

/// The triple of the machine the tests run on, from `rustc -vV`.
fn host_triple() -> String {
    let out = Command::new("rustc")
        .arg("-vV")
        .output()
        .expect("cannot run rustc");
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .find_map(|l| l.strip_prefix("host: "))
        .expect("rustc -vV names the host")
        .to_string()
}

/// `cargo metadata` of the workspace, for this machine's platform (so that no other
/// platform's crates need fetching).
fn metadata() -> Value {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--offline",
            "--filter-platform",
        ])
        .arg(host_triple())
        .current_dir(caravan_tests::workspace_root())
        .output()
        .expect("cannot run cargo metadata");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("cargo metadata prints JSON")
}

/// Workspace package name → (its directory relative to the root, its normal dependencies
/// that are workspace packages).
fn workspace_graph(meta: &Value) -> BTreeMap<String, (String, BTreeSet<String>)> {
    let root = meta["workspace_root"].as_str().unwrap().to_string();
    let members: BTreeSet<&str> = meta["workspace_members"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(Value::as_str)
        .collect();
    let mut names = BTreeMap::new();
    let mut dirs = BTreeMap::new();
    for p in meta["packages"].as_array().unwrap() {
        let id = p["id"].as_str().unwrap();
        if members.contains(id) {
            let name = p["name"].as_str().unwrap().to_string();
            let manifest = p["manifest_path"].as_str().unwrap();
            let dir = manifest
                .strip_prefix(&root)
                .unwrap_or(manifest)
                .trim_start_matches('/')
                .trim_end_matches("Cargo.toml")
                .trim_end_matches('/')
                .to_string();
            names.insert(id.to_string(), name.clone());
            dirs.insert(name, dir);
        }
    }
    let mut graph = BTreeMap::new();
    for node in meta["resolve"]["nodes"].as_array().unwrap() {
        let Some(name) = names.get(node["id"].as_str().unwrap()) else {
            continue;
        };
        let deps = node["deps"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|d| {
                d["dep_kinds"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .any(|k| k["kind"].is_null())
            })
            .filter_map(|d| names.get(d["pkg"].as_str().unwrap()).cloned())
            .collect();
        graph.insert(name.clone(), (dirs[name].clone(), deps));
    }
    graph
}

/// Every workspace package `from` depends on, directly or not.
fn closure(graph: &BTreeMap<String, (String, BTreeSet<String>)>, from: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    let mut todo = vec![from.to_string()];
    while let Some(p) = todo.pop() {
        for d in &graph[&p].1 {
            if seen.insert(d.clone()) {
                todo.push(d.clone());
            }
        }
    }
    seen
}

#[test]
fn the_launcher_depends_on_no_process_or_scenario_crate() {
    let graph = workspace_graph(&metadata());
    let deps = closure(&graph, "caravan-cli");
    let upward: Vec<String> = deps
        .iter()
        .filter(|d| !graph[*d].0.starts_with("runtime") && graph[*d].0 != "schemas")
        .map(|d| format!("{d} ({})", graph[d].0))
        .collect();
    assert!(
        upward.is_empty(),
        "caravan-cli depends on {upward:?}; it may use only runtime/ and schemas/ crates"
    );
    // The arrows below the launcher point down too.
    assert!(deps.contains("caravan") && deps.contains("caravan-report"));
    assert!(!closure(&graph, "caravan").contains("caravan-report"));
    assert!(closure(&graph, "caravan-schemas").is_empty());
}
