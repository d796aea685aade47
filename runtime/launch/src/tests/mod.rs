//! Unit tests of launch files: one file (`mod.rs`), includes, links, templates, arguments and
//! report entries.

mod args;
mod docs;
mod fuzz;
mod include;
mod links;
mod report;
mod template;

use super::load::*;
use super::model::*;
use caravan::ClockMode;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

/// Line numbers in the tests below refer to this file.
const BASE: &str = r#"[group]
name = "convoy"
seed = 7

[hosts.sim]
[hosts.rpi-0]
cpu_slowdown = 12.0

[[links]]
between = ["rpi-*", "sim"]
latency = "6ms"

[[process]]
name = "physics"
exec = "caravan-physics"
host = "sim"
rate = "500Hz"

[[process]]
name = "planner"
exec = "planner --fast"
on = "robot/0/scan"
"#;

/// A fresh directory per call, so tests can run in parallel.
pub fn temp_dir() -> PathBuf {
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    let n = NEXT.fetch_add(1, Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("caravan-launch-{}-{n}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub fn resolve(name: &str) -> Option<PathBuf> {
    ["caravan-physics", "planner", "sleep"]
        .contains(&name)
        .then(|| PathBuf::from("/usr/bin").join(name))
}

pub fn load_text(text: &str, sets: &[&str]) -> Result<LaunchFile, LaunchError> {
    let path = temp_dir().join("launch.toml");
    std::fs::write(&path, text).unwrap();
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    load(&path, &sets, &resolve)
}

/// The error's lines, with the temp file's path replaced by FILE.
pub fn errors(text: &str, sets: &[&str]) -> Vec<String> {
    let path = temp_dir().join("launch.toml");
    std::fs::write(&path, text).unwrap();
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let err = load(&path, &sets, &resolve).expect_err("should be rejected");
    assert_eq!(err.exit_code(), 2);
    let shown = err.to_string().replace(&path.display().to_string(), "FILE");
    shown.lines().map(str::to_string).collect()
}

/// Writes `files` (relative name, text) into a fresh directory and returns it.
pub fn write_files(files: &[(&str, &str)]) -> PathBuf {
    let dir = temp_dir();
    for (name, text) in files {
        let path = dir.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    dir
}

/// Loads `top` of `dir` with `sets`.
pub fn load_in(dir: &std::path::Path, top: &str, sets: &[&str]) -> Result<LaunchFile, LaunchError> {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    load(&dir.join(top), &sets, &resolve)
}

/// The error's lines for `top` of `dir`, with the directory left out of paths.
pub fn errors_in(dir: &std::path::Path, top: &str, sets: &[&str]) -> Vec<String> {
    let err = load_in(dir, top, sets).expect_err("should be rejected");
    assert_eq!(err.exit_code(), 2);
    let shown = err.to_string().replace(&format!("{}/", dir.display()), "");
    shown.lines().map(str::to_string).collect()
}

pub fn edited(from: &str, to: &str) -> String {
    assert!(BASE.contains(from), "{from}");
    BASE.replacen(from, to, 1)
}

pub fn assert_error(lines: &[String], expected: &str) {
    assert!(
        lines.iter().any(|l| l == expected),
        "expected {expected:?} among:\n{}",
        lines.join("\n")
    );
}

#[test]
fn launch_valid_file_with_defaults() {
    let lf = load_text(BASE, &[]).unwrap();
    assert_eq!(lf.group.name, "convoy");
    assert_eq!(lf.group.clock, ClockMode::Lockstep);
    assert_eq!(lf.group.duration, None);
    assert_eq!(lf.group.seed, 7);
    assert_eq!(lf.group.tick, Duration::from_millis(1));
    assert_eq!(lf.group.grace, Duration::from_secs(3));
    assert!(lf.group.record.is_empty());
    assert_eq!(lf.hosts["sim"].cpu_slowdown, None);
    assert_eq!(lf.hosts["rpi-0"].cpu_slowdown, Some(12.0));
    let link = &lf.links[0];
    assert_eq!(link.between, ["rpi-*".to_string(), "sim".to_string()]);
    assert_eq!(
        (link.latency, link.jitter),
        (Duration::from_millis(6), Duration::ZERO)
    );
    assert_eq!((link.loss, link.bandwidth_bps), (0.0, None));
    let physics = &lf.processes[0];
    assert_eq!(physics.exec, Exec::Workspace("caravan-physics".into()));
    assert_eq!(physics.host, "sim");
    assert_eq!(physics.rate.as_deref(), Some("500Hz"));
    assert_eq!(physics.params, serde_json::json!({}));
    assert_eq!(physics.restart, Restart::Never);
    assert_eq!(physics.restart_backoff, Duration::from_millis(500));
    assert_eq!((physics.max_restarts, physics.required), (3, true));
    assert!(physics.env.is_empty() && physics.args.is_empty());
    let planner = &lf.processes[1];
    assert_eq!(
        planner.exec,
        Exec::Command(vec!["planner".into(), "--fast".into()])
    );
    assert_eq!(planner.host, "localhost");
    assert_eq!(planner.on.as_deref(), Some("robot/0/scan"));
    assert_eq!(lf.resolved_toml, BASE);
}

#[test]
fn launch_every_key_set() {
    let text = r#"
[group]
name = "full"
clock = "realtime"
duration = "180s"
seed = 1
tick = "2ms"
record = ["robot/*/pose_true", "map"]
grace = "1s"

[hosts.a]
[hosts.b]
cpu_slowdown = 2

[[links]]
between = ["a", "b"]
jitter = "3ms"
loss = 0.005
bandwidth = "54Mbit"

[[process]]
name = "p"
exec = "sleep 'a b'"
args = ["-v"]
host = "b"
params = { world = "lab.toml", count = 5, nested = { x = [1.5, true] } }
restart = "on-failure"
restart_backoff = "1s"
max_restarts = 9
required = false
env = { RUST_LOG = "info" }
"#;
    let lf = load_text(text, &[]).unwrap();
    assert_eq!(lf.group.clock, ClockMode::Realtime);
    assert_eq!(lf.group.duration, Some(Duration::from_secs(180)));
    assert_eq!(lf.group.tick, Duration::from_millis(2));
    assert_eq!(lf.group.record, ["robot/*/pose_true", "map"]);
    assert_eq!(lf.group.grace, Duration::from_secs(1));
    assert_eq!(lf.hosts["b"].cpu_slowdown, Some(2.0));
    assert_eq!(lf.links[0].bandwidth_bps, Some(54_000_000));
    assert_eq!(lf.links[0].loss, 0.005);
    let p = &lf.processes[0];
    assert_eq!(p.exec, Exec::Command(vec!["sleep".into(), "a b".into()]));
    assert_eq!(p.args, ["-v"]);
    assert_eq!(
        p.params,
        serde_json::json!({"world": "lab.toml", "count": 5, "nested": {"x": [1.5, true]}})
    );
    assert_eq!(p.restart, Restart::OnFailure);
    assert_eq!((p.max_restarts, p.required), (9, false));
    assert_eq!(p.env["RUST_LOG"], "info");
}

#[test]
fn launch_typo_key_suggests() {
    let lines = errors(&edited("rate = \"500Hz\"", "rat = \"500Hz\""), &[]);
    assert_eq!(
        lines,
        ["FILE:17: process 'physics', key 'rat': unknown key; did you mean 'rate'?"]
    );
    let lines = errors(&edited("seed = 7", "sed = 7"), &[]);
    assert_error(
        &lines,
        "FILE:3: group, key 'sed': unknown key; did you mean 'seed'?",
    );
    let lines = errors(&edited("[[process]]", "[[proces]]"), &[]);
    assert!(lines[0].starts_with("FILE:13: key 'proces': unknown key; did you mean 'process'?"));
    let lines = errors(&edited("cpu_slowdown", "cpu_slowdwn"), &[]);
    assert_error(
        &lines,
        "FILE:7: host 'rpi-0', key 'cpu_slowdwn': unknown key; did you mean 'cpu_slowdown'?",
    );
    let lines = errors(&edited("latency", "latncy"), &[]);
    assert_error(
        &lines,
        "FILE:11: link #1, key 'latncy': unknown key; did you mean 'latency'?",
    );
}

#[test]
fn launch_wrong_type() {
    let lines = errors(&edited("seed = 7", "seed = \"seven\""), &[]);
    assert_eq!(
        lines,
        ["FILE:3: group, key 'seed': expected a non-negative integer, found string \"seven\""]
    );
    let lines = errors(&edited("host = \"sim\"", "host = 3"), &[]);
    assert_error(
        &lines,
        "FILE:16: process 'physics', key 'host': expected a string, found integer 3",
    );
}

#[test]
fn launch_unknown_exec() {
    let lines = errors(&edited("\"planner --fast\"", "\"plannr --fast\""), &[]);
    assert_eq!(
        lines,
        [
            "FILE:21: process 'planner', key 'exec': unknown executable 'plannr': not a workspace binary and not on PATH"
        ]
    );
    let lines = errors(&edited("\"caravan-physics\"", "\"./bin/physics\""), &[]);
    assert!(
        lines[0].starts_with(
            "FILE:15: process 'physics', key 'exec': unknown executable './bin/physics'"
        )
    );
    assert!(lines[0].ends_with("does not exist"), "{}", lines[0]);
}

#[test]
fn launch_exec_path_relative_to_file() {
    use std::os::unix::fs::PermissionsExt;
    let dir = temp_dir();
    std::fs::create_dir_all(dir.join("bin")).unwrap();
    let program = dir.join("bin/sim");
    std::fs::write(&program, "#!/bin/sh\n").unwrap();
    std::fs::set_permissions(&program, std::fs::Permissions::from_mode(0o755)).unwrap();
    let path = dir.join("launch.toml");
    std::fs::write(&path, edited("\"caravan-physics\"", "\"bin/sim --x\"")).unwrap();
    let lf = load(&path, &[], &resolve).unwrap();
    assert_eq!(
        lf.processes[0].exec,
        Exec::Command(vec!["bin/sim".into(), "--x".into()])
    );
}

#[test]
fn launch_duplicate_names() {
    let lines = errors(&edited("name = \"planner\"", "name = \"physics\""), &[]);
    assert_eq!(
        lines,
        [
            "FILE:20: process 'physics', key 'name': 'physics' is already the name of an earlier process (line 14)"
        ]
    );
}

#[test]
fn launch_bad_duration_and_rate() {
    let lines = errors(&edited("latency = \"6ms\"", "latency = \"6 parsecs\""), &[]);
    assert_eq!(lines.len(), 1);
    assert!(lines[0].starts_with("FILE:11: link #1, key 'latency': '6 parsecs' is not a duration"));
    let lines = errors(&edited("rate = \"500Hz\"", "rate = \"fast\""), &[]);
    assert_eq!(
        lines,
        [
            "FILE:17: process 'physics', key 'rate': 'fast' is not a rate; write a frequency like \"50Hz\" or a period like \"20ms\""
        ]
    );
    let lines = errors(&edited("seed = 7", "tick = \"0s\""), &[]);
    assert_error(
        &lines,
        "FILE:3: group, key 'tick': must be greater than zero",
    );
}

#[test]
fn launch_missing_file() {
    let path = temp_dir().join("nope.toml");
    let err = load(&path, &[], &resolve).unwrap_err();
    assert_eq!(err.exit_code(), 2);
    let shown = err.to_string();
    assert!(
        shown.starts_with(&format!("cannot read launch file {}: ", path.display())),
        "{shown}"
    );
}

#[test]
fn launch_syntax_error_has_line_and_column() {
    let lines = errors(&edited("seed = 7", "seed = = 7"), &[]);
    assert_eq!(lines.len(), 1);
    assert!(
        lines[0].starts_with("FILE:3:8: TOML syntax error: "),
        "{}",
        lines[0]
    );
    let lines = errors(&edited("seed = 7", "name = \"again\""), &[]);
    assert!(
        lines[0].starts_with("FILE:3:1: TOML syntax error: duplicate key"),
        "{}",
        lines[0]
    );
}

#[test]
fn launch_overrides_apply_and_keep_line_numbers() {
    let text = edited("rate = \"500Hz\"", "rat = \"500Hz\"");
    // group.duration adds a line inside [group]; the later error must keep its own line.
    let lines = errors(&text, &["group.duration=10s", "group.seed=3"]);
    assert_eq!(
        lines,
        ["FILE:17: process 'physics', key 'rat': unknown key; did you mean 'rate'?"]
    );
    let lf = load_text(
        BASE,
        &[
            "group.seed=3",
            "process.physics.rate=250Hz",
            "process.planner.params.k=1",
        ],
    )
    .unwrap();
    assert_eq!(lf.group.seed, 3);
    assert_eq!(lf.processes[0].rate.as_deref(), Some("250Hz"));
    assert_eq!(lf.processes[1].params, serde_json::json!({"k": 1}));
    assert!(
        lf.resolved_toml.contains("seed = 3\n"),
        "{}",
        lf.resolved_toml
    );
    assert!(lf.resolved_toml.contains("rate = \"250Hz\""));
}

#[test]
fn launch_args_substitute_and_unknown_args_are_named() {
    let text = format!("[args]\nk = 4\nrate = \"250Hz\"\n{BASE}")
        .replace("rate = \"500Hz\"", "rate = \"$(arg rate)\"");
    let lf = load_text(&text, &["process.planner.params.k=\"$(arg k)\""]).unwrap();
    assert_eq!(lf.processes[0].rate.as_deref(), Some("250Hz"));
    assert_eq!(lf.processes[1].params, serde_json::json!({"k": 4}));
    let lf = load_text(&text, &["args.rate=20Hz"]).unwrap();
    assert_eq!(lf.processes[0].rate.as_deref(), Some("20Hz"));
    let lines = errors(&text.replace("$(arg rate)", "$(arg rte)"), &[]);
    assert_eq!(
        lines,
        ["FILE:20: '$(arg rte)' names no argument in [args]; did you mean 'rate'?"]
    );
    let lines = errors(&text, &["args.rat=1Hz"]);
    assert_eq!(
        lines,
        ["--set args.rat=1Hz: 'args' has no key 'rat'; did you mean 'rate'?"]
    );
}

#[test]
fn launch_bad_override() {
    let lines = errors(BASE, &["process.phyiscs.rate=1Hz", "group.seed=abc"]);
    assert_eq!(
        lines,
        [
            "--set process.phyiscs.rate=1Hz: no process 'phyiscs'; did you mean 'physics'?",
            "--set group.seed=abc: group, key 'seed': expected a non-negative integer, found string \"abc\"",
        ]
    );
    let lines = errors(BASE, &["process.physics.colour=red"]);
    assert_eq!(
        lines,
        [
            "--set process.physics.colour=red: process 'physics', key 'colour': unknown key; expected one of: name, exec, args, host, rate, on, spin, params, restart, restart_backoff, max_restarts, required, ends_group, env, check, container"
        ]
    );
}

/// A value that cannot be passed is blamed where it was written: on the `--set` that wrote it,
/// or on the file's line, with the path inside `params` named.
#[test]
fn launch_nan_param_is_blamed_on_its_writer() {
    let text = BASE.replace(
        "on = \"robot/0/scan\"",
        "on = \"robot/0/scan\"\nparams = { k = 1.0 }",
    );
    let lines = errors(&text, &["process.planner.params.gain=nan"]);
    assert_eq!(
        lines,
        [
            "--set process.planner.params.gain=nan: process 'planner', key 'params': params.gain: NaN cannot be passed as a parameter"
        ]
    );
    let lines = errors(&text, &["process.planner.params.deep.list=[1.0, inf]"]);
    assert_eq!(
        lines,
        [
            "--set process.planner.params.deep.list=[1.0, inf]: process 'planner', key 'params': params.deep.list: inf cannot be passed as a parameter"
        ]
    );
    let lines = errors(
        &text.replace("k = 1.0", "k = nan"),
        &["process.planner.params.gain=2"],
    );
    assert_eq!(
        lines,
        ["FILE:23: process 'planner', key 'params': params.k: NaN cannot be passed as a parameter"]
    );
}

#[test]
fn launch_unknown_host() {
    let lines = errors(&edited("host = \"sim\"", "host = \"sym\""), &[]);
    assert_eq!(
        lines,
        [
            "FILE:16: process 'physics', key 'host': host 'sym' is not declared under [hosts]; did you mean 'sim'?"
        ]
    );
    // Without [hosts], only this machine is known.
    let text = BASE.replace("[hosts.sim]\n[hosts.rpi-0]\ncpu_slowdown = 12.0\n", "");
    let text = text.replace(
        "[[links]]\nbetween = [\"rpi-*\", \"sim\"]\nlatency = \"6ms\"\n",
        "",
    );
    let err = load_text(&text, &[]).unwrap_err().to_string();
    assert!(
        err.contains("key 'host': host 'sim' is not declared: the file has no [hosts] table"),
        "{err}"
    );
    let text = text.replace("host = \"sim\"", "host = \"localhost\"");
    assert_eq!(
        load_text(&text, &[]).unwrap().processes[0].host,
        "localhost"
    );
}

#[test]
fn launch_rate_and_on() {
    let lines = errors(
        &edited("rate = \"500Hz\"", "rate = \"500Hz\"\non = \"tick\""),
        &[],
    );
    assert_eq!(
        lines,
        ["FILE:17: process 'physics', key 'rate': set either 'rate' or 'on', not both"]
    );
    let lines = errors(BASE, &["process.planner.rate=1Hz"]);
    assert_eq!(
        lines,
        [
            "--set process.planner.rate=1Hz: process 'planner', key 'rate': set either 'rate' or 'on', not both"
        ]
    );
}

#[test]
fn launch_range_checks() {
    let text = edited("cpu_slowdown = 12.0", "cpu_slowdown = 0.5")
        .replace("latency = \"6ms\"", "loss = 1.5\nbandwidth = \"54Mb\"");
    let lines = errors(
        &text,
        &["process.physics.restart=on_failure", "group.name=bad_name"],
    );
    assert_error(
        &lines,
        "FILE:7: host 'rpi-0', key 'cpu_slowdown': must be 1.0 to 1e6 (1.0 = as fast as this machine), found 0.5",
    );
    assert_error(
        &lines,
        "FILE:11: link #1, key 'loss': must be between 0.0 and 1.0, found 1.5",
    );
    assert!(lines.iter().any(|l| {
        l.starts_with("FILE:12: link #1, key 'bandwidth': '54Mb' is not a bandwidth")
    }));
    assert_error(
        &lines,
        "--set process.physics.restart=on_failure: process 'physics', key 'restart': 'on_failure' is not a restart policy; did you mean 'on-failure'?",
    );
    assert_error(
        &lines,
        "--set group.name=bad_name: group, key 'name': group name 'bad_name' contains '_'; use letters, digits and '-'",
    );
    assert_eq!(lines.len(), 5, "{lines:?}");
}

#[test]
fn launch_missing_required() {
    let text = BASE
        .replace("name = \"convoy\"\n", "")
        .replace("exec = \"planner --fast\"\n", "");
    let lines = errors(&text, &[]);
    assert_eq!(
        lines,
        [
            "FILE:1: group: missing required key 'name'",
            "FILE:18: process 'planner': missing required key 'exec'",
        ]
    );
    let lines = errors("[[process]]\nname = \"a\"\nexec = \"sleep\"\n", &[]);
    assert_eq!(
        lines,
        ["FILE: file: missing [group] table with at least name = \"…\""]
    );
}

#[test]
fn launch_inline_lists_and_host_names() {
    let text = r#"group = { name = "g" }
hosts = { "a b" = {}, ok = { cpu_slowdown = 1 } }
process = [
  { name = "one", exec = "sleep", host = "ok" },
  { name = "two", exec = "sleep", rte = "1Hz" },
]
"#;
    let lines = errors(text, &[]);
    assert_eq!(
        lines,
        [
            "FILE:2: host 'a b': host names use letters, digits, '-', '_' and '.'",
            "FILE:5: process 'two', key 'rte': unknown key; did you mean 'rate'?",
        ]
    );
    let lf = load_text(
        &text.replace("\"a b\" = {}, ", "").replace("rte", "rate"),
        &[],
    )
    .unwrap();
    assert_eq!(lf.processes[1].rate.as_deref(), Some("1Hz"));
}
