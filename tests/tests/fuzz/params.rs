//! Mutation fuzzing of the scenarios' params (issue 49): the params table of every process
//! and report plugin of the shipped IMU, contact, tracked and UAV launch files, as the file
//! gives it, written as TOML (as a `[process.params]` table) and edited at random
//! (`caravan_report::fuzz::mutate`: numbers replaced by 0, −1, 1e308, NaN, huge integers…,
//! strings by empty, long or path-like values, lines deleted, duplicated or swapped), then
//! checked as the launcher checks it before the start: by the program itself, run with
//! `CARAVAN_CHECK=1` (`check_processes`), a report plugin with `--check`. Each input must pass
//! or be refused with a message, never make the program panic, die of a signal or hang.
//!
//! An input that is no longer a TOML table (about 63 %) is refused with its launch file,
//! before any check; each other costs one check's process (2 to 3 ms in a debug build). CI
//! runs 2,000 inputs (about 7 s);
//! `PROPTEST_CASES=… cargo nextest run -p caravan-tests --test fuzz -E 'test(fuzz_scenario)'`
//! is the long run (docs/reliability.md).

use super::config;
use caravan_group::run::preflight::check_processes;
use caravan_launch::load::load_source;
use caravan_launch::model::{Exec, LaunchFile};
use caravan_report::ReportEntry;
use caravan_report::fuzz::mutate;
use caravan_tests::{workspace_bin, workspace_root};
use proptest::prelude::*;
use std::path::PathBuf;
use std::time::Duration;

/// The most any one check may take: far more than any takes, far less than a hang.
const BOUND: Duration = Duration::from_secs(30);

/// The shipped launch files whose params are fuzzed: every scenario's but the convoy's, whose
/// processes' params `fuzz_launch_loader_never_panics` and the range tests cover.
const FILES: &[&str] = &[
    "imu/rotation.toml",
    "imu/tilt.toml",
    "imu/lift.toml",
    "imu/lift-force-sensor.toml",
    "imu/arm.toml",
    "imu/spinup.toml",
    "imu/allan.toml",
    "contact/push.toml",
    "tracked/flat.toml",
    "tracked/step.toml",
    "uav/encounter.toml",
];

/// One params table to fuzz: a process (a launch file holding that process alone, its
/// program given by its path and always checked) or a report plugin.
#[derive(Clone)]
enum Target {
    Process(Box<LaunchFile>),
    Report(ReportEntry),
}

impl Target {
    fn params(&self) -> &serde_json::Value {
        match self {
            Target::Process(lf) => &lf.processes[0].params,
            Target::Report(entry) => &entry.params,
        }
    }

    /// What the check found wrong with `params` (`None`: nothing).
    fn check(&self, params: serde_json::Value) -> Option<String> {
        match self.clone() {
            Target::Process(mut lf) => {
                lf.processes[0].params = params;
                let problems = check_processes(&lf);
                (!problems.is_empty()).then(|| {
                    let all: Vec<String> = problems.into_iter().map(|p| p.message).collect();
                    all.join("; ")
                })
            }
            Target::Report(mut entry) => {
                entry.params = params;
                caravan_group::report::check(&entry).err()
            }
        }
    }
}

/// The workspace's program `name`, by its path, if it is one.
fn program(name: &str) -> Option<PathBuf> {
    let dir = workspace_bin("caravan").parent()?.to_path_buf();
    let path = dir.join(name);
    path.is_file().then_some(path)
}

/// The program of `exec` when it is one of the workspace's, as a command line of its path.
fn own_program(exec: &Exec) -> Option<Vec<String>> {
    let words = match exec {
        Exec::Workspace(name) => vec![name.clone()],
        Exec::Command(words) => words.clone(),
    };
    let (first, rest) = words.split_first()?;
    let path = program(first)?;
    let mut line = vec![path.to_str()?.to_string()];
    line.extend(rest.iter().cloned());
    Some(line)
}

/// Every process and report plugin of [`FILES`] run by a workspace program, each with its
/// params as its file gives them; each passes its check as shipped.
fn targets() -> Vec<Target> {
    let mut targets = Vec::new();
    for file in FILES {
        let path = workspace_root().join("launch").join(file);
        let lf = load_source(&path, None, &[], &program, &|_| Vec::new())
            .unwrap_or_else(|e| panic!("{file}: {e}"));
        for p in &lf.processes {
            let Some(line) = own_program(&p.exec) else {
                continue;
            };
            let mut one = lf.clone();
            let mut spec = p.clone();
            spec.exec = Exec::Command(line);
            spec.check = Some(true);
            one.processes = vec![spec];
            targets.push(Target::Process(Box::new(one)));
        }
        for r in &lf.reports {
            let Some(exec) = own_program(&r.exec) else {
                continue;
            };
            targets.push(Target::Report(ReportEntry {
                exec,
                params: r.params.clone(),
                launch_dir: r.launch_dir.display().to_string(),
                timeout_s: BOUND.as_secs_f64(),
            }));
        }
    }
    for t in &targets {
        assert_eq!(t.check(t.params().clone()), None, "shipped params refused");
    }
    assert!(targets.len() > 20, "{} targets", targets.len());
    targets
}

/// `params` as a launch file writes them: a TOML table (nested tables as `[a.b]`).
fn as_toml(params: &serde_json::Value) -> String {
    toml::to_string(&toml::Value::try_from(params).unwrap()).unwrap()
}

/// What a check must never say: that its program panicked, died of a signal or ran past
/// its limit.
fn assert_clear(message: &str, params: &str) {
    for bad in [
        "panicked",
        "exited 101",
        "killed by a signal",
        "did not end within",
        "did not finish within",
        "RUST_BACKTRACE",
    ] {
        assert!(!message.contains(bad), "{bad}: {message}\nparams: {params}");
    }
}

proptest! {
    #![proptest_config(config(2000))]

    #[test]
    fn fuzz_scenario_params_never_panic(pick in any::<usize>(), seed in any::<u64>()) {
        thread_local!(static TARGETS: Vec<Target> = targets());
        let target = TARGETS.with(|t| t[pick % t.len()].clone());
        let text = mutate(&as_toml(target.params()), seed);
        // What does not read as a table is refused with the launch file, before any check.
        let Ok(table) = toml::from_str::<toml::Table>(&text) else {
            return Ok(());
        };
        let params = serde_json::to_value(table).unwrap();
        // A check that hangs is cut by its own time limit (a plugin's `BOUND`, a process's
        // check limit) and said so, which `assert_clear` refuses; no clock is read here.
        if let Some(message) = target.check(params) {
            assert_clear(&message, &text);
        }
    }
}
