//! Checking every process's params and inputs before the group starts. Each Caravan program
//! runs once with `CARAVAN_CHECK=1`: it reads its params, world and robot description as it
//! would to run, and exits 0, or 2 with a message naming the key, without joining the group
//! (`caravan::node_main`, `caravan.main` in Python). A bad param of any process then stops
//! the launch before anything started, as a bad key of the launch file does.

use caravan_launch::model::{EntryList, EntryProblem, LaunchFile};
use crossbeam::channel::{RecvTimeoutError, bounded};
use std::collections::HashMap;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// How long a check may take. Generous: a Python agent's first check creates its virtual
/// environment and installs its packages.
pub const CHECK_TIMEOUT: Duration = Duration::from_secs(600);

/// Checks already run, by everything a check is given: a sweep loads its launch file once per
/// cell, and cells mostly differ in one process's params, so the other processes' checks (and
/// report plugins') would be run again on the same input for every cell. A check reads only
/// its command line, environment and the files they name, which a sweep does not change while
/// it validates. Checks that timed out or could not start are not kept.
#[derive(Default)]
pub struct CheckMemo {
    processes: Known<Output>,
    reports: Known<Result<(), String>>,
}

impl CheckMemo {
    /// A report plugin's check of `entry` (`PROGRAM --check`), unless it was run on the same
    /// command line, params, directory and time limit before.
    pub fn report(&self, entry: &caravan_report::ReportEntry) -> Result<(), String> {
        let key = format!(
            "{:?}\0{}\0{}\0{}",
            entry.exec, entry.params, entry.launch_dir, entry.timeout_s
        );
        if let Some(known) = self.reports.get(&key) {
            return known;
        }
        let result = crate::report::check(entry);
        self.reports.keep(key, &result);
        result
    }
}

/// The outcomes of checks already run, by their key: one map for the processes' checks
/// (which run at once and are kept as each ends) and the report plugins' (run one by one).
struct Known<V>(Mutex<HashMap<String, V>>);

impl<V> Default for Known<V> {
    fn default() -> Self {
        Self(Mutex::default())
    }
}

impl<V: Clone> Known<V> {
    fn get(&self, key: &str) -> Option<V> {
        self.0.lock().unwrap().get(key).cloned()
    }

    fn keep(&self, key: String, outcome: &V) {
        self.0.lock().unwrap().insert(key, outcome.clone());
    }
}

/// Everything a check's process is given, as one string (the inherited environment is the
/// launcher's, the same for every check).
fn memo_key(cmd: &Command) -> String {
    let envs: Vec<_> = cmd.get_envs().collect();
    let args: Vec<_> = cmd.get_args().collect();
    format!(
        "{:?}\0{args:?}\0{envs:?}\0{:?}",
        cmd.get_program(),
        cmd.get_current_dir()
    )
}

/// Runs the checks of `lf`'s processes at once and returns what they found wrong.
pub fn check_processes(lf: &LaunchFile) -> Vec<EntryProblem> {
    check_processes_with(lf, None)
}

/// [`check_processes`], taking known outcomes from `memo` and adding new ones to it.
pub fn check_processes_with(lf: &LaunchFile, memo: Option<&CheckMemo>) -> Vec<EntryProblem> {
    let mut env = match super::group_environment(lf) {
        Ok(env) => env,
        Err(e) => {
            return vec![problem(
                0,
                format!("cannot describe the group's network: {e:#}"),
            )];
        }
    };
    env.insert(caravan::env_vars::CHECK.into(), "1".into());
    let mut running = Vec::new();
    let mut problems = Vec::new();
    let mut facts = Vec::new();
    for (index, plan) in super::plan(lf).into_iter().enumerate() {
        if !is_checked(&plan) {
            continue;
        }
        let name = plan.spec.name.clone();
        // A check holds no shared memory, and one blocked in a read would sit out a SIGTERM:
        // it is killed outright if the launcher dies.
        let mut cmd = plan.command(&env, libc::SIGKILL);
        let key = memo.map(|_| memo_key(&cmd));
        let known = memo.zip(key.as_ref()).and_then(|(m, k)| m.processes.get(k));
        if let Some(output) = known {
            facts.extend(caravan::facts::read(&String::from_utf8_lossy(
                &output.stdout,
            )));
            let params = &plan.spec.params;
            problems.extend(judge(index, &name, &plan.program, params, Ok(output)));
            continue;
        }
        // Its standard output holds the facts it states (`caravan::facts`).
        let child = cmd.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn();
        match child {
            Ok(child) => {
                let (tx, rx) = bounded(1);
                let pid = child.id() as i32;
                std::thread::spawn(move || {
                    let _ = tx.send(child.wait_with_output());
                });
                let entry = (index, name, plan.program, plan.spec.params.clone(), key);
                running.push((entry, pid, rx));
            }
            Err(e) => problems.push(problem(
                index,
                format!(
                    "process '{name}': cannot run {}: {e}",
                    plan.program.display()
                ),
            )),
        }
    }
    let deadline = Instant::now() + CHECK_TIMEOUT;
    for ((index, name, program, params, key), pid, rx) in running {
        // A check longer than a few seconds is said once, so a slow one is not taken for a hang.
        let said = Instant::now() + Duration::from_secs(10);
        let mut received =
            rx.recv_timeout(said.min(deadline).saturating_duration_since(Instant::now()));
        if matches!(received, Err(RecvTimeoutError::Timeout)) && Instant::now() < deadline {
            eprintln!(
                "caravan: still checking process '{name}' (up to {} s; a Python agent's first \
                 check installs its packages)",
                CHECK_TIMEOUT.as_secs()
            );
            received = rx.recv_timeout(deadline.saturating_duration_since(Instant::now()));
        }
        let output = match received {
            Ok(output) => {
                if let (Some(memo), Some(key), Ok(output)) = (memo, key, &output) {
                    memo.processes.keep(key, output);
                }
                if let Ok(output) = &output {
                    facts.extend(caravan::facts::read(&String::from_utf8_lossy(
                        &output.stdout,
                    )));
                }
                output
            }
            Err(RecvTimeoutError::Timeout) => {
                // SAFETY: kill(2) on the process group of a child we spawned and not reaped.
                unsafe { libc::kill(-pid, libc::SIGKILL) };
                let _ = rx.recv();
                problems.push(problem(
                    index,
                    format!(
                        "process '{name}': its check of its params did not end within {} s; \\
                         set `check = false` for a program that does not understand CARAVAN_CHECK",
                        CHECK_TIMEOUT.as_secs()
                    ),
                ));
                continue;
            }
            Err(RecvTimeoutError::Disconnected) => continue,
        };
        if let Some(p) = judge(index, &name, &program, &params, output) {
            problems.push(p);
        }
    }
    problems.extend(super::robots::served_robots_are_simulated(lf, &facts));
    problems
}

/// Whether the launcher checks this process before the start (and, in realtime, expects a
/// status from it): its `check` key, else whether it is one of Caravan's own programs.
pub fn is_checked(plan: &super::supervisor::Planned) -> bool {
    plan.spec
        .check
        .unwrap_or_else(|| is_caravan_program(&plan.program))
}

/// Caravan's own programs understand `CARAVAN_CHECK`: those built in this workspace (beside
/// the `caravan` binary) and Python agents started through `caravan-python`.
fn is_caravan_program(program: &Path) -> bool {
    let beside = std::env::current_exe()
        .ok()
        .and_then(|exe| exe.parent().map(Path::to_path_buf));
    program
        .parent()
        .is_some_and(|dir| Some(dir) == beside.as_deref())
        || program.file_name().is_some_and(|f| f == "caravan-python")
}

fn judge(
    index: usize,
    name: &str,
    program: &Path,
    params: &serde_json::Value,
    output: std::io::Result<Output>,
) -> Option<EntryProblem> {
    let output = match output {
        Ok(output) if output.status.success() => return None,
        Ok(output) => output,
        Err(e) => return Some(problem(index, format!("process '{name}': {e}"))),
    };
    let stderr = String::from_utf8_lossy(&output.stderr);
    let text = tidy(stderr.trim(), name, program);
    let named = named_key(text);
    let found = named
        .is_none()
        .then(|| key_of_quoted_value(text, params))
        .flatten();
    let message = match (output.status.code(), text.is_empty()) {
        (_, false) => match &found {
            Some(key) => format!("process '{name}', key '{key}': {text}"),
            None => format!("process '{name}': {text}"),
        },
        (Some(code), true) => format!("process '{name}': its check exited {code}"),
        (None, true) => format!("process '{name}': its check was killed by a signal"),
    };
    let key = named.or(found);
    Some(EntryProblem {
        list: EntryList::Process,
        index,
        key,
        message,
    })
}

/// The node's message without what the launcher says anyway: the program name before it and
/// "params of node 'NAME': ".
fn tidy<'a>(text: &'a str, name: &str, program: &Path) -> &'a str {
    let mut text = text;
    if let Some(file) = program.file_name().and_then(|f| f.to_str())
        && let Some(rest) = text.strip_prefix(file).and_then(|t| t.strip_prefix(": "))
    {
        text = rest;
    }
    let prefix = format!("params of node '{name}': ");
    text.strip_prefix(prefix.as_str()).unwrap_or(text)
}

/// The params key a message names as `key 'a.b'`, the form `caravan::parse_params` and the
/// processes' checks use.
fn named_key(text: &str) -> Option<String> {
    let start = text.find("key '")? + 5;
    let len = text[start..].find('\'')?;
    Some(text[start..start + len].to_string()).filter(|k| !k.is_empty())
}

/// The params key a message that names none is about, found by the value it quotes (serde
/// names no key inside an internally tagged enum: `invalid type: string "steep", expected
/// f64`), or by the kind of value it names (`invalid type: sequence, expected f64`). Only a
/// value that exactly one key holds names it.
fn key_of_quoted_value(text: &str, params: &serde_json::Value) -> Option<String> {
    use serde_json::Value;
    let quoted = quoted_value(text)?;
    let mut found = Vec::new();
    values(params, String::new(), &mut |path, value| {
        let same = match (&quoted, value) {
            (Quoted::Sequence, Value::Array(_)) | (Quoted::Map, Value::Object(_)) => true,
            (Quoted::Scalar(q), Value::String(s)) => *q == format!("\"{s}\""),
            // A number or boolean as serde prints it (`1.5`, `3`, `true`).
            (Quoted::Scalar(q), v @ (Value::Number(_) | Value::Bool(_))) => {
                *q == serde_json::to_string(v).unwrap_or_default()
            }
            _ => false,
        };
        if same {
            found.push(path);
        }
    });
    match found.as_slice() {
        [one] => Some(one.clone()),
        _ => None,
    }
}

/// The bad value serde's message names.
enum Quoted {
    /// `string "x"` (quotes kept), `` integer `3` ``, `` floating point `1.5` `` or
    /// `` boolean `true` `` (the value).
    Scalar(String),
    /// `sequence`: an array.
    Sequence,
    /// `map`: a table.
    Map,
}

fn quoted_value(text: &str) -> Option<Quoted> {
    let after = |marker: &str| text.find(marker).map(|i| &text[i + marker.len()..]);
    if let Some(rest) = after("string \"") {
        let end = rest.find('"')?;
        return Some(Quoted::Scalar(format!("\"{}\"", &rest[..end])));
    }
    if text.contains("invalid type: sequence,") {
        return Some(Quoted::Sequence);
    }
    if text.contains("invalid type: map,") {
        return Some(Quoted::Map);
    }
    let rest = (after("integer `").or_else(|| after("floating point `")))
        .or_else(|| after("boolean `"))?;
    Some(Quoted::Scalar(rest[..rest.find('`')?].to_string()))
}

/// Calls `f` with the dotted path (`a.b[2].c`) and value of every value inside `v`, tables
/// and arrays before what they hold.
fn values(v: &serde_json::Value, path: String, f: &mut dyn FnMut(String, &serde_json::Value)) {
    if !path.is_empty() {
        f(path.clone(), v);
    }
    match v {
        serde_json::Value::Object(map) => {
            for (k, child) in map {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                values(child, p, f);
            }
        }
        serde_json::Value::Array(list) => {
            for (i, child) in list.iter().enumerate() {
                values(child, format!("{path}[{i}]"), f);
            }
        }
        _ => {}
    }
}

/// A report plugin's refusal of its params (`PROGRAM --check` said `text`), at the key it
/// names, found as for a process.
pub fn report_problem(
    index: usize,
    exec: &str,
    params: &serde_json::Value,
    text: &str,
) -> EntryProblem {
    // Without what the launcher says anyway: "PROGRAM: params of report 'PROGRAM': ".
    let program = exec.split_whitespace().next().unwrap_or(exec);
    let file = Path::new(program)
        .file_name()
        .and_then(|f| f.to_str())
        .unwrap_or(program);
    let text = text.strip_prefix(&format!("{file}: ")).unwrap_or(text);
    let text = text
        .strip_prefix(&format!("params of report '{file}': "))
        .unwrap_or(text);
    let named = named_key(text);
    let found = named
        .is_none()
        .then(|| key_of_quoted_value(text, params))
        .flatten();
    let message = match &found {
        Some(key) => format!("report '{exec}', key '{key}': {text}"),
        None => format!("report '{exec}': {text}"),
    };
    EntryProblem {
        list: EntryList::Report,
        index,
        key: named.or(found),
        message,
    }
}

fn problem(index: usize, message: String) -> EntryProblem {
    EntryProblem {
        list: EntryList::Process,
        index,
        key: None,
        message,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn preflight_finds_the_named_key() {
        assert_eq!(
            named_key("key 'poses[0].x': expected f64").as_deref(),
            Some("poses[0].x")
        );
        assert_eq!(named_key("cannot read world.toml"), None);
    }

    #[test]
    fn preflight_finds_the_key_of_a_quoted_value() {
        let params = serde_json::json!({
            "scenario": "tilt", "angle_deg": "steep", "poses": [{"x": 1.5}], "n": 3, "m": 3
        });
        let key = |text| key_of_quoted_value(text, &params);
        let text = r#"invalid type: string "steep", expected f64"#;
        assert_eq!(key(text).as_deref(), Some("angle_deg"));
        let text = "invalid type: floating point `1.5`, expected u32";
        assert_eq!(key(text).as_deref(), Some("poses[0].x"));
        // One array, one table: each named by its kind.
        let nested = serde_json::json!({"offset": [1.0, 2.0], "arm": {"r": 0.1}, "x": 1.0});
        let text = "invalid type: sequence, expected f64";
        assert_eq!(
            key_of_quoted_value(text, &nested).as_deref(),
            Some("offset")
        );
        let text = "invalid type: map, expected f64";
        assert_eq!(key_of_quoted_value(text, &nested).as_deref(), Some("arm"));
        let text = "invalid type: boolean `true`, expected f64";
        let params = serde_json::json!({"scenario": "tilt", "angle_deg": true, "n": 3});
        assert_eq!(
            key_of_quoted_value(text, &params).as_deref(),
            Some("angle_deg")
        );
        // Two keys hold 3: neither is named.
        assert_eq!(key("invalid type: integer `3`, expected a string"), None);
        assert_eq!(key("cannot read world.toml"), None);
    }

    #[test]
    fn preflight_drops_what_the_launcher_says_anyway() {
        let text = "caravan-physics: params of node 'physics': key 'substeps': must be at least 1";
        assert_eq!(
            tidy(text, "physics", Path::new("/x/caravan-physics")),
            "key 'substeps': must be at least 1"
        );
    }
}
