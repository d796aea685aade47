//! The world and robot-description loaders under mutation fuzzing: shipped files, edited at
//! random (`caravan_report::fuzz`), must load or give an error, never panic. CI runs 2,000
//! worlds and 400 robot descriptions; `PROPTEST_CASES=1000000 cargo nextest run --release -p caravan-tests
//! --test fuzz` is the long run (docs/reliability.md). `fuzz/inputs.rs` fuzzes recordings,
//! hosts tables and policy files the same way, `fuzz/params.rs` the scenarios' params as
//! their programs check them before a start.

#[path = "fuzz/inputs.rs"]
mod inputs;
#[path = "fuzz/params.rs"]
mod params;

use caravan_report::fuzz::mutate;
use caravan_tests::workspace_root;
use caravan_world::description::parse;
use caravan_world::world::parse_world;
use proptest::prelude::*;
use std::path::{Path, PathBuf};

/// `PROPTEST_CASES` inputs, else `ci`.
fn config(ci: u32) -> ProptestConfig {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(ci);
    ProptestConfig {
        cases,
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

/// The shipped files of the scenarios' `kind` folders (`worlds`, `robots`) with this extension.
fn shipped(kind: &str, ext: &str) -> Vec<(PathBuf, String)> {
    let mut files = Vec::new();
    for scenario in std::fs::read_dir(workspace_root().join("launch"))
        .unwrap()
        .flatten()
    {
        for f in std::fs::read_dir(scenario.path().join(kind))
            .into_iter()
            .flatten()
            .flatten()
        {
            let path = f.path();
            if path.extension().is_some_and(|e| e == ext) {
                let text = std::fs::read_to_string(&path).unwrap();
                files.push((path, text));
            }
        }
    }
    files.sort();
    assert!(!files.is_empty());
    files
}

proptest! {
    #![proptest_config(config(2000))]

    #[test]
    fn fuzz_world_loader_never_panics(pick in any::<usize>(), seed in any::<u64>()) {
        thread_local!(static WORLDS: Vec<(PathBuf, String)> = shipped("worlds", "toml"));
        let text = WORLDS.with(|w| mutate(&w[pick % w.len()].1, seed));
        let _ = parse_world(&text);
    }
}

proptest! {
    // The tracked robots' descriptions are large: fewer inputs in CI.
    #![proptest_config(config(400))]

    #[test]
    fn fuzz_robot_description_loader_never_panics(pick in any::<usize>(), seed in any::<u64>()) {
        thread_local!(static ROBOTS: Vec<(PathBuf, String)> = shipped("robots", "urdf"));
        let (dir, text) = ROBOTS.with(|r| {
            let (path, text) = &r[pick % r.len()];
            (path.parent().unwrap_or(Path::new(".")).to_path_buf(), mutate(text, seed))
        });
        if let Ok(d) = parse(&text, "fuzz.urdf", &dir) {
            // A description that loads gives a mass without panicking too.
            let _ = d.mass();
        }
    }
}
