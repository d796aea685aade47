//! The workspace's dependency arrows point down: schemas ← runtime ← the launcher's libraries
//! ← the `caravan` command; processes and scenarios build on the runtime, never the other way
//! round. Within the runtime's and the launcher's crates, no files import each other in a
//! circle, and no crate outgrows 6,000 lines. `docs/architecture.md` draws the same layers.

use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
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
        .filter(|d| !graph[*d].0.starts_with("runtime") && !graph[*d].0.starts_with("schemas"))
        .map(|d| format!("{d} ({})", graph[d].0))
        .collect();
    assert!(
        upward.is_empty(),
        "caravan-cli depends on {upward:?}; it may use only runtime/ and schemas/ crates"
    );
    // The arrows below the launcher point down too.
    assert!(deps.contains("caravan") && deps.contains("caravan-report"));
    assert!(!closure(&graph, "caravan").contains("caravan-report"));
    let schemas = closure(&graph, "caravan-schemas");
    assert!(
        schemas.iter().all(|d| d == "caravan-schemas-derive"),
        "{schemas:?}"
    );
}

/// The layers of the runtime's and the launcher's crates, bottom first: a crate may depend
/// only on crates of lower layers. Every crate under `runtime/` and `schemas/` is listed.
const LAYERS: &[&[&str]] = &[
    &["caravan-schemas-derive"],
    &["caravan-schemas"],
    &["caravan-network"],
    &["caravan"],
    &["caravan-lockstep"],
    &["caravan-report", "caravan-ros2"],
    &["caravan-launch"],
    &["caravan-record"],
    &["caravan-bridge"],
    &["caravan-group"],
    &["caravan-sweep", "caravan-bench"],
    &["caravan-cli"],
];

fn layer_of(name: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&name))
}

#[test]
fn the_launchers_crates_depend_only_on_lower_layers() {
    let graph = workspace_graph(&metadata());
    let mut wrong = Vec::new();
    for (name, (dir, deps)) in &graph {
        if !(dir.starts_with("runtime") || dir.starts_with("schemas")) {
            continue;
        }
        let Some(layer) = layer_of(name) else {
            wrong.push(format!("{name} ({dir}) is in no layer of LAYERS"));
            continue;
        };
        for d in deps {
            match layer_of(d) {
                Some(l) if l < layer => {}
                _ => wrong.push(format!("{name} depends on {d}, which is not below it")),
            }
        }
    }
    assert!(wrong.is_empty(), "{wrong:#?}");
    // Loading a launch file touches no shared memory.
    let launch = closure(&graph, "caravan-launch");
    assert!(!launch.contains("caravan-record") && !launch.contains("caravan-group"));
}

/// The `.rs` files under `dir`, recursively.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            out.extend(rust_files(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
    out.sort();
    out
}

/// Module path (`["run", "driver"]`) → file, for a crate's `src` (binaries under `bin/` and
/// test modules under `tests/` left out).
fn module_files(src: &Path) -> BTreeMap<Vec<String>, PathBuf> {
    let mut mods = BTreeMap::new();
    for path in rust_files(src) {
        let rel = path.strip_prefix(src).unwrap().with_extension("");
        let mut segs: Vec<String> = rel
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect();
        if matches!(
            segs.last().map(String::as_str),
            Some("mod" | "lib" | "main")
        ) {
            segs.pop();
        }
        if segs.first().is_some_and(|s| s == "bin") || segs.iter().any(|s| s == "tests") {
            continue;
        }
        mods.insert(segs, path);
    }
    mods
}

/// The paths a file names with `crate::…` or `super::…` (grouped `use` items included), each
/// as (`crate` or `super`, its segments). Unit tests at the end of a file are left out.
fn references(text: &str) -> Vec<(bool, Vec<String>)> {
    let text = match text.find("#[cfg(test)]\nmod tests") {
        Some(at) => &text[..at],
        None => text,
    };
    let ident = |c: char| c.is_ascii_alphanumeric() || c == '_';
    let mut out = Vec::new();
    for (at, root) in text
        .match_indices("crate::")
        .chain(text.match_indices("super::"))
    {
        if text[..at].chars().next_back().is_some_and(ident) {
            continue;
        }
        let is_crate = root == "crate::";
        let mut segs = Vec::new();
        let mut rest = &text[at + root.len()..];
        loop {
            let end = rest.find(|c: char| !ident(c)).unwrap_or(rest.len());
            if end > 0 {
                segs.push(rest[..end].to_string());
            }
            rest = &rest[end..];
            let group = match segs.is_empty() {
                true => rest.strip_prefix('{'),
                false => rest.strip_prefix("::{"),
            };
            if let Some(r) = group {
                // A grouped `use`: each item's first segment.
                let items = &r[..r.find('}').unwrap_or(r.len())];
                for item in items.split(',') {
                    let first = item.trim().split("::").next().unwrap_or("").trim();
                    if !first.is_empty() && first != "self" {
                        let mut path = segs.clone();
                        path.push(first.to_string());
                        out.push((is_crate, path));
                    }
                }
                break;
            }
            match rest.strip_prefix("::") {
                Some(r) if r.starts_with(ident) => rest = r,
                _ => break,
            }
        }
        out.push((is_crate, segs));
    }
    out
}

/// Groups of two or more files of one crate that import each other, directly or not.
fn import_circles(src: &Path) -> Vec<Vec<PathBuf>> {
    let mods = module_files(src);
    let files: Vec<&PathBuf> = mods.values().collect();
    let index: BTreeMap<&PathBuf, usize> = files.iter().enumerate().map(|(i, f)| (*f, i)).collect();
    let mut edges = vec![BTreeSet::new(); files.len()];
    for (module, path) in &mods {
        let text = std::fs::read_to_string(path).unwrap();
        for (is_crate, segs) in references(&text) {
            let base: &[String] = if is_crate {
                &[]
            } else {
                &module[..module.len().saturating_sub(1)]
            };
            let full: Vec<String> = base.iter().cloned().chain(segs).collect();
            if let Some(target) = (1..=full.len()).rev().find_map(|k| mods.get(&full[..k]))
                && target != path
            {
                edges[index[path]].insert(index[target]);
            }
        }
    }
    strongly_connected(&edges)
        .into_iter()
        .filter(|c| c.len() > 1)
        .map(|c| c.into_iter().map(|i| files[i].clone()).collect())
        .collect()
}

/// Tarjan's strongly connected components of a graph given as adjacency sets.
fn strongly_connected(edges: &[BTreeSet<usize>]) -> Vec<Vec<usize>> {
    struct State<'a> {
        edges: &'a [BTreeSet<usize>],
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        stack: Vec<usize>,
        on_stack: Vec<bool>,
        next: usize,
        out: Vec<Vec<usize>>,
    }
    fn visit(s: &mut State, v: usize) {
        s.index[v] = Some(s.next);
        s.low[v] = s.next;
        s.next += 1;
        s.stack.push(v);
        s.on_stack[v] = true;
        for &w in s.edges[v].iter() {
            match s.index[w] {
                None => {
                    visit(s, w);
                    s.low[v] = s.low[v].min(s.low[w]);
                }
                Some(i) if s.on_stack[w] => s.low[v] = s.low[v].min(i),
                Some(_) => {}
            }
        }
        if Some(s.low[v]) == s.index[v] {
            let mut component = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack[w] = false;
                component.push(w);
                if w == v {
                    break;
                }
            }
            s.out.push(component);
        }
    }
    let n = edges.len();
    let mut s = State {
        edges,
        index: vec![None; n],
        low: vec![0; n],
        stack: Vec::new(),
        on_stack: vec![false; n],
        next: 0,
        out: Vec::new(),
    };
    for v in 0..n {
        if s.index[v].is_none() {
            visit(&mut s, v);
        }
    }
    s.out
}

/// The runtime's and the launcher's crates: every package under `runtime/`, and `schemas/`.
fn launcher_crates() -> Vec<PathBuf> {
    let graph = workspace_graph(&metadata());
    let root = caravan_tests::workspace_root();
    graph
        .values()
        .filter(|(dir, _)| dir.starts_with("runtime") || dir.starts_with("schemas"))
        .map(|(dir, _)| root.join(dir))
        .collect()
}

#[test]
fn no_files_of_the_launchers_crates_import_each_other_in_a_circle() {
    let root = caravan_tests::workspace_root();
    let circles: Vec<String> = launcher_crates()
        .iter()
        .flat_map(|c| import_circles(&c.join("src")))
        .map(|files| {
            let names: Vec<String> = files
                .iter()
                .map(|f| f.strip_prefix(&root).unwrap().display().to_string())
                .collect();
            names.join(" ↔ ")
        })
        .collect();
    assert!(circles.is_empty(), "import circles: {circles:#?}");
}

#[test]
fn the_circle_finder_finds_a_circle() {
    let dir = std::env::temp_dir().join(format!("caravan-layout-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("a")).unwrap();
    std::fs::write(dir.join("lib.rs"), "mod a;\nmod b;\n").unwrap();
    std::fs::write(dir.join("a/mod.rs"), "use crate::b::B;\nmod c;\n").unwrap();
    std::fs::write(dir.join("a/c.rs"), "use super::super::b;\n").unwrap();
    std::fs::write(dir.join("b.rs"), "use crate::{a::A, x};\npub struct B;\n").unwrap();
    let circles = import_circles(&dir);
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(circles.len(), 1, "{circles:?}");
    let names: BTreeSet<String> = circles[0]
        .iter()
        .map(|f| f.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, BTreeSet::from(["mod.rs".into(), "b.rs".into()]));
}

#[test]
fn no_crate_is_over_six_thousand_lines() {
    let root = caravan_tests::workspace_root();
    let graph = workspace_graph(&metadata());
    let big: Vec<String> = graph
        .values()
        .filter_map(|(dir, _)| {
            let src = root.join(dir).join("src");
            if !src.is_dir() {
                return None;
            }
            let lines: usize = rust_files(&src)
                .iter()
                .map(|f| std::fs::read_to_string(f).unwrap().lines().count())
                .sum();
            (lines > 6000).then(|| format!("{dir}: {lines} lines"))
        })
        .collect();
    assert!(big.is_empty(), "crates over 6,000 lines: {big:?}");
}
