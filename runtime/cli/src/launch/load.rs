//! Reads a launch file, applies `--set` overrides and validates everything, collecting every
//! problem found so the user can fix them in one go. Nothing is started on any error.

use super::args;
use super::model::*;
use super::overrides::{self, Applied, Seg};
use super::suggest;
use caravan::ClockMode;
use std::collections::{BTreeMap, HashMap};
use std::fmt;
use std::path::{Path, PathBuf};
use std::time::Duration;
use toml_edit::{Document, Item, TableLike, Value};

const TOP_KEYS: &[&str] = &["args", "group", "hosts", "links", "process"];
const GROUP_KEYS: &[&str] = &[
    "name",
    "clock",
    "duration",
    "seed",
    "tick",
    "record",
    "grace",
    "step_timeout",
];
const HOST_KEYS: &[&str] = &["cpu_slowdown"];
const LINK_KEYS: &[&str] = &[
    "between",
    "latency",
    "jitter",
    "distribution",
    "loss",
    "spike_probability",
    "spike",
    "bandwidth",
];
const PROCESS_KEYS: &[&str] = &[
    "name",
    "exec",
    "args",
    "host",
    "rate",
    "on",
    "params",
    "restart",
    "restart_backoff",
    "max_restarts",
    "required",
    "env",
];

/// Why a launch file cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum LaunchError {
    #[error("cannot read launch file {}: {reason}", path.display())]
    Read { path: PathBuf, reason: String },
    /// Every problem found, one per line, in file order (overrides first).
    #[error("{}", lines(.0))]
    Invalid(Vec<Problem>),
}

impl LaunchError {
    /// Bad input, as opposed to a failure while running.
    #[allow(dead_code)] // the launcher has its own EXIT_BAD_INPUT (also 2) for now
    pub fn exit_code(&self) -> i32 {
        2
    }
}

fn lines(problems: &[Problem]) -> String {
    let lines: Vec<String> = problems.iter().map(Problem::to_string).collect();
    lines.join("\n")
}

/// One problem: where (`file:line`, `file:line:col` or `--set KEY=VALUE`) and what.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    pub location: String,
    /// For ordering; `None` for overrides and whole-file problems.
    pub line: Option<usize>,
    pub message: String,
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.location, self.message)
    }
}

/// Loads and validates `path` with `overrides` (`KEY=VALUE`) applied. `resolve_exec` finds a
/// bare program name (workspace binaries, then PATH).
pub fn load(
    path: &Path,
    overrides: &[String],
    resolve_exec: &dyn Fn(&str) -> Option<PathBuf>,
) -> Result<LaunchFile, LaunchError> {
    let text = std::fs::read_to_string(path).map_err(|e| LaunchError::Read {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    let original = Document::parse(text.as_str()).map_err(|e| syntax_error(path, &text, &e))?;
    let mut doc = original.clone().into_mut();
    let (applied, rejected) = overrides::apply(&mut doc, overrides);
    let unresolved = args::substitute(&mut doc);
    let mut check = Checker {
        file: path,
        original: &original,
        applied: &applied,
        resolve_exec,
        problems: rejected
            .into_iter()
            .map(|r| Problem {
                location: format!("--set {}", r.text),
                line: None,
                message: r.message,
            })
            .collect(),
        silenced: Vec::new(),
    };
    let root = Scope {
        table: doc.as_table(),
        path: Vec::new(),
        label: String::new(),
    };
    for u in unresolved {
        check.problem(&u.path, u.message);
        // The unresolved reference is the problem; its value's own errors would only echo it.
        check.silenced.push(u.path);
    }
    check.unknown_keys(&root, TOP_KEYS);
    let group = check.group(&root);
    let hosts = check.hosts(&root);
    let links = check.links(&root, &hosts);
    let processes = check.processes(&root, &hosts);
    if !check.problems.is_empty() {
        let mut problems = check.problems;
        problems.sort_by_key(|p| p.line.unwrap_or(0));
        return Err(LaunchError::Invalid(problems));
    }
    Ok(LaunchFile {
        path: path.to_path_buf(),
        group,
        hosts,
        links,
        processes,
        resolved_toml: doc.to_string(),
    })
}

fn syntax_error(path: &Path, text: &str, e: &toml_edit::TomlError) -> LaunchError {
    let offset = e.span().map_or(0, |s| s.start).min(text.len());
    let line = line_at(text, offset);
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let col = text[line_start..offset].chars().count() + 1;
    LaunchError::Invalid(vec![Problem {
        location: format!("{}:{line}:{col}", path.display()),
        line: Some(line),
        message: format!("TOML syntax error: {}", e.message().trim()),
    }])
}

fn line_at(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// A table being validated: where it is, and how messages name it ("process 'physics'").
struct Scope<'d> {
    table: &'d dyn TableLike,
    path: Vec<Seg>,
    label: String,
}

impl<'d> Scope<'d> {
    fn at(&self, key: &str) -> Vec<Seg> {
        let mut path = self.path.clone();
        path.push(Seg::Key(key.to_string()));
        path
    }

    fn get(&self, key: &str) -> Option<&'d Item> {
        self.table.get(key)
    }
}

struct Checker<'a> {
    file: &'a Path,
    original: &'a Document<&'a str>,
    applied: &'a [Applied],
    resolve_exec: &'a dyn Fn(&str) -> Option<PathBuf>,
    problems: Vec<Problem>,
    /// Paths whose further problems are not reported.
    silenced: Vec<Vec<Seg>>,
}

impl Checker<'_> {
    // ---- reporting ----

    /// Records a problem at `path`: blamed on the override that set it, else on its line in
    /// the file as written (looked up there, so added override lines never shift numbers).
    fn problem(&mut self, path: &[Seg], message: String) {
        if self.silenced.iter().any(|s| path.starts_with(s)) {
            return;
        }
        let blamed = self
            .applied
            .iter()
            .rev()
            .find(|a| path.starts_with(&a.path));
        let (location, line) = match blamed {
            Some(a) => (format!("--set {}", a.text), None),
            None => match self.line_of(path) {
                Some(l) => (format!("{}:{l}", self.file.display()), Some(l)),
                None => (self.file.display().to_string(), None),
            },
        };
        self.problems.push(Problem {
            location,
            line,
            message,
        });
    }

    fn key_problem(&mut self, s: &Scope, key: &str, message: impl fmt::Display) {
        let what = if s.label.is_empty() {
            format!("key '{key}': {message}")
        } else {
            format!("{}, key '{key}': {message}", s.label)
        };
        self.problem(&s.at(key), what);
    }

    fn scope_problem(&mut self, s: &Scope, message: impl fmt::Display) {
        let label = if s.label.is_empty() { "file" } else { &s.label };
        self.problem(&s.path, format!("{label}: {message}"));
    }

    /// The line of the deepest part of `path` found in the original document.
    fn line_of(&self, path: &[Seg]) -> Option<usize> {
        let mut table: &dyn TableLike = self.original.as_table();
        let mut offset = None;
        let mut segs = path.iter().peekable();
        while let Some(Seg::Key(k)) = segs.next() {
            let Some((key, item)) = table.get_key_value(k) else {
                break;
            };
            offset = key
                .span()
                .or_else(|| item.span())
                .map(|s| s.start)
                .or(offset);
            let next: Option<&dyn TableLike> = match (segs.peek(), item) {
                (Some(Seg::Index(i)), Item::ArrayOfTables(a)) => {
                    segs.next();
                    a.get(*i).map(|t| {
                        offset = t.span().map(|s| s.start).or(offset);
                        t as &dyn TableLike
                    })
                }
                (Some(Seg::Index(i)), Item::Value(Value::Array(a))) => {
                    segs.next();
                    a.get(*i).and_then(|v| {
                        offset = v.span().map(|s| s.start).or(offset);
                        v.as_inline_table().map(|t| t as &dyn TableLike)
                    })
                }
                _ => item.as_table_like(),
            };
            match next {
                Some(t) => table = t,
                None => break,
            }
        }
        offset.map(|o| line_at(self.original.raw(), o))
    }

    // ---- reading values ----

    fn unknown_keys(&mut self, s: &Scope, allowed: &[&str]) {
        for (key, _) in s.table.iter() {
            if !allowed.contains(&key) {
                let hint = suggest::hint(key, allowed);
                self.key_problem(s, key, format!("unknown key{hint}"));
            }
        }
    }

    /// The value of `key` converted, or `None` when absent or wrong (the latter reported).
    fn get<T>(
        &mut self,
        s: &Scope,
        key: &str,
        convert: impl FnOnce(&Item) -> Result<T, String>,
    ) -> Option<T> {
        match convert(s.get(key)?) {
            Ok(v) => Some(v),
            Err(message) => {
                self.key_problem(s, key, message);
                None
            }
        }
    }

    fn required<T>(
        &mut self,
        s: &Scope,
        key: &str,
        convert: impl FnOnce(&Item) -> Result<T, String>,
    ) -> Option<T> {
        if s.get(key).is_none() {
            self.scope_problem(s, format!("missing required key '{key}'"));
        }
        self.get(s, key, convert)
    }

    /// Opens the sub-table `key` of `parent`, checking its keys against `allowed` if given.
    fn table<'d>(
        &mut self,
        parent: &Scope<'d>,
        key: &str,
        label: String,
        allowed: Option<&[&str]>,
    ) -> Option<Scope<'d>> {
        let item = parent.get(key)?;
        let Some(table) = item.as_table_like() else {
            self.key_problem(
                parent,
                key,
                format!("expected a table, found {}", found(item)),
            );
            return None;
        };
        let scope = Scope {
            table,
            path: parent.at(key),
            label,
        };
        if let Some(allowed) = allowed {
            self.unknown_keys(&scope, allowed);
        }
        Some(scope)
    }

    /// The entries of `[[key]]` (or `key = [{…}, …]`) with their index.
    fn list<'d>(&mut self, parent: &Scope<'d>, key: &str) -> Vec<(usize, &'d dyn TableLike)> {
        let mut out = Vec::new();
        match parent.get(key) {
            None => {}
            Some(Item::ArrayOfTables(a)) => {
                out.extend(a.iter().enumerate().map(|(i, t)| (i, t as &dyn TableLike)));
            }
            Some(Item::Value(Value::Array(a))) => {
                for (i, v) in a.iter().enumerate() {
                    match v.as_inline_table() {
                        Some(t) => out.push((i, t as &dyn TableLike)),
                        None => {
                            let mut path = parent.at(key);
                            path.push(Seg::Index(i));
                            let msg = format!("{key} entry {}: expected a table", i + 1);
                            self.problem(&path, msg);
                        }
                    }
                }
            }
            Some(other) => {
                let msg = format!("expected [[{key}]] tables, found {}", found(other));
                self.key_problem(parent, key, msg);
            }
        }
        out
    }

    // ---- the sections ----

    fn group(&mut self, root: &Scope) -> GroupSpec {
        let mut group = GroupSpec {
            name: String::new(),
            clock: ClockMode::Lockstep,
            duration: None,
            seed: 0,
            tick: GroupSpec::DEFAULT_TICK,
            record: Vec::new(),
            grace: GroupSpec::DEFAULT_GRACE,
            step_timeout: GroupSpec::DEFAULT_STEP_TIMEOUT,
        };
        let Some(s) = self.table(root, "group", "group".into(), Some(GROUP_KEYS)) else {
            if root.get("group").is_none() {
                self.scope_problem(root, "missing [group] table with at least name = \"…\"");
            }
            return group;
        };
        if let Some(name) = self.required(&s, "name", string) {
            if let Err(e) = caravan::group::validate_name(&name) {
                self.key_problem(&s, "name", e);
            }
            group.name = name;
        }
        group.clock = self
            .get(&s, "clock", |i| string(i)?.parse::<ClockMode>())
            .unwrap_or(ClockMode::Lockstep);
        group.duration = self.get(&s, "duration", positive_duration);
        group.seed = self.get(&s, "seed", unsigned).unwrap_or(0);
        group.tick = self
            .get(&s, "tick", positive_duration)
            .unwrap_or(GroupSpec::DEFAULT_TICK);
        group.record = self.get(&s, "record", patterns).unwrap_or_default();
        group.grace = self
            .get(&s, "grace", duration)
            .unwrap_or(GroupSpec::DEFAULT_GRACE);
        group.step_timeout = self
            .get(&s, "step_timeout", positive_duration)
            .unwrap_or(GroupSpec::DEFAULT_STEP_TIMEOUT);
        group
    }

    fn hosts(&mut self, root: &Scope) -> BTreeMap<String, HostSpec> {
        let mut hosts = BTreeMap::new();
        let Some(s) = self.table(root, "hosts", "hosts".into(), None) else {
            return hosts;
        };
        for (name, _) in s.table.iter() {
            let label = format!("host '{name}'");
            let Some(h) = self.table(&s, name, label, Some(HOST_KEYS)) else {
                continue;
            };
            if name.is_empty()
                || !name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
            {
                self.scope_problem(&h, "host names use letters, digits, '-', '_' and '.'");
            }
            let cpu_slowdown = self.get(&h, "cpu_slowdown", |i| {
                let f = number(i)?;
                if f.is_finite() && f >= 1.0 {
                    Ok(f)
                } else {
                    Err(format!(
                        "must be at least 1.0 (1.0 = as fast as this machine), found {f}"
                    ))
                }
            });
            hosts.insert(name.to_string(), HostSpec { cpu_slowdown });
        }
        hosts
    }

    fn links(&mut self, root: &Scope, hosts: &BTreeMap<String, HostSpec>) -> Vec<LinkSpec> {
        let mut links = Vec::new();
        for (i, table) in self.list(root, "links") {
            let s = self.open(
                table,
                root.at("links"),
                i,
                format!("link #{}", i + 1),
                LINK_KEYS,
            );
            let between = self.required(&s, "between", |item| {
                let list = strings(item)?;
                <[String; 2]>::try_from(list)
                    .map_err(|l| format!("expected exactly two host patterns, found {}", l.len()))
            });
            for pattern in between.iter().flatten() {
                if !hosts.keys().any(|h| glob_match(pattern, h)) {
                    let hint = if hosts.is_empty() {
                        "; declare hosts as [hosts.NAME] tables".to_string()
                    } else {
                        suggest::did_you_mean(pattern, hosts.keys().map(String::as_str))
                    };
                    let msg = format!("pattern '{pattern}' matches no declared host{hint}");
                    self.key_problem(&s, "between", msg);
                }
            }
            let link = LinkSpec {
                between: between.unwrap_or_default(),
                latency: self.get(&s, "latency", duration).unwrap_or_default(),
                jitter: self.get(&s, "jitter", duration).unwrap_or_default(),
                distribution: self
                    .get(&s, "distribution", |i| match string(i)?.as_str() {
                        "uniform" => Ok(caravan::network::Jitter::Uniform),
                        "normal" => Ok(caravan::network::Jitter::Normal),
                        "exponential" => Ok(caravan::network::Jitter::Exponential),
                        other => Err(format!(
                            "'{other}' is not a jitter distribution; use uniform, normal or exponential"
                        )),
                    })
                    .unwrap_or_default(),
                loss: self.get(&s, "loss", probability).unwrap_or(0.0),
                spike_probability: self
                    .get(&s, "spike_probability", probability)
                    .unwrap_or(0.0),
                spike: self
                    .get(&s, "spike", |i| {
                        let list = strings(i)?;
                        let [lo, hi] = <[String; 2]>::try_from(list).map_err(|l| {
                            format!("expected two durations [min, max], found {}", l.len())
                        })?;
                        let parse = |t: &str| caravan::parse_duration(t).map_err(|e| e.to_string());
                        let (lo, hi) = (parse(&lo)?, parse(&hi)?);
                        if lo > hi {
                            return Err("the spike's minimum exceeds its maximum".to_string());
                        }
                        Ok([lo, hi])
                    })
                    .unwrap_or_default(),
                bandwidth_bps: self.get(&s, "bandwidth", |i| parse_bandwidth(&string(i)?)),
            };
            links.push(link);
        }
        links
    }

    /// A scope for entry `index` of the list at `path`, checking its keys against `allowed`.
    fn open<'d>(
        &mut self,
        table: &'d dyn TableLike,
        mut path: Vec<Seg>,
        index: usize,
        label: String,
        allowed: &[&str],
    ) -> Scope<'d> {
        path.push(Seg::Index(index));
        let scope = Scope { table, path, label };
        self.unknown_keys(&scope, allowed);
        scope
    }

    fn processes(&mut self, root: &Scope, hosts: &BTreeMap<String, HostSpec>) -> Vec<ProcessSpec> {
        let entries = self.list(root, "process");
        if entries.is_empty() && root.get("process").is_none() {
            self.scope_problem(root, "no [[process]] entries; a group needs at least one");
        }
        let mut first_use: HashMap<String, Vec<Seg>> = HashMap::new();
        let mut processes = Vec::new();
        for (i, table) in entries {
            let label = match table.get("name").and_then(Item::as_str) {
                Some(name) => format!("process '{name}'"),
                None => format!("process #{}", i + 1),
            };
            let s = self.open(table, root.at("process"), i, label, PROCESS_KEYS);
            let name = self.required(&s, "name", string).unwrap_or_default();
            let named = table.get("name").is_some_and(Item::is_str);
            if let Some(first) = first_use.get(&name) {
                let at = self
                    .line_of(first)
                    .map(|l| format!(" (line {l})"))
                    .unwrap_or_default();
                self.key_problem(
                    &s,
                    "name",
                    format!("'{name}' is already the name of an earlier process{at}"),
                );
            } else if named {
                first_use.insert(name.clone(), s.at("name"));
            }
            if named && !is_process_name(&name) {
                self.key_problem(
                    &s,
                    "name",
                    format!("'{name}' must be made of letters, digits, '_' and '-'"),
                );
            }
            processes.push(self.process(&s, name, hosts));
        }
        processes
    }

    fn process(
        &mut self,
        s: &Scope,
        name: String,
        hosts: &BTreeMap<String, HostSpec>,
    ) -> ProcessSpec {
        let exec = self.exec(s);
        let host = self.get(s, "host", string);
        if let Some(h) = &host
            && !hosts.is_empty()
            && !hosts.contains_key(h)
        {
            let hint = suggest::hint(h, &hosts.keys().map(String::as_str).collect::<Vec<_>>());
            self.key_problem(
                s,
                "host",
                format!("host '{h}' is not declared under [hosts]{hint}"),
            );
        }
        let rate = self.get(s, "rate", |i| {
            let text = string(i)?;
            caravan::parse_rate(&text).map_err(|e| e.to_string())?;
            Ok(text)
        });
        let on = self.get(s, "on", |i| {
            let topic = string(i)?;
            if topic.is_empty() || topic.contains(char::is_whitespace) {
                return Err(format!("'{topic}' is not a topic name"));
            }
            Ok(topic)
        });
        if s.get("rate").is_some() && s.get("on").is_some() {
            // Point at whichever an override set, since that is the one the user just typed.
            let key = if self.applied.iter().any(|a| a.path == s.at("on")) {
                "on"
            } else {
                "rate"
            };
            self.key_problem(s, key, "set either 'rate' or 'on', not both");
        }
        ProcessSpec {
            name,
            exec: exec.unwrap_or(Exec::Command(Vec::new())),
            args: self.get(s, "args", strings).unwrap_or_default(),
            host: host.unwrap_or_else(|| ProcessSpec::DEFAULT_HOST.to_string()),
            rate,
            on,
            params: self
                .get(s, "params", params)
                .unwrap_or_else(|| serde_json::Value::Object(Default::default())),
            restart: self.get(s, "restart", restart).unwrap_or_default(),
            restart_backoff: self
                .get(s, "restart_backoff", duration)
                .unwrap_or(ProcessSpec::DEFAULT_BACKOFF),
            max_restarts: self
                .get(s, "max_restarts", |i| {
                    u32::try_from(unsigned(i)?)
                        .map_err(|_| "expected at most 4294967295".to_string())
                })
                .unwrap_or(ProcessSpec::DEFAULT_MAX_RESTARTS),
            required: self.get(s, "required", boolean).unwrap_or(true),
            env: self.get(s, "env", env).unwrap_or_default(),
        }
    }

    /// Splits `exec` like a shell would and checks that its program exists.
    fn exec(&mut self, s: &Scope) -> Option<Exec> {
        let dir = self.file.parent().unwrap_or(Path::new(""));
        let resolve = self.resolve_exec;
        self.required(s, "exec", |item| {
            let text = string(item)?;
            let words = shlex::split(&text)
                .ok_or_else(|| format!("cannot split '{text}': unbalanced quotes"))?;
            let Some(program) = words.first().cloned() else {
                return Err("the command is empty".into());
            };
            if program.contains('/') {
                let full = dir.join(&program);
                if !is_executable(&full) {
                    let why = if full.exists() {
                        "is not an executable file"
                    } else {
                        "does not exist"
                    };
                    return Err(format!(
                        "unknown executable '{program}': {} {why}",
                        full.display()
                    ));
                }
                return Ok(Exec::Command(words));
            }
            if resolve(&program).is_none() {
                return Err(format!(
                    "unknown executable '{program}': not a workspace binary and not on PATH"
                ));
            }
            Ok(if words.len() == 1 {
                Exec::Workspace(program)
            } else {
                Exec::Command(words)
            })
        })
    }
}

// ---- converters: an item to a typed value, or a message saying what was expected ----

fn found(item: &Item) -> String {
    match item {
        Item::Value(Value::String(s)) => format!("string {:?}", s.value()),
        Item::Value(Value::Integer(i)) => format!("integer {}", i.value()),
        Item::Value(Value::Float(f)) => format!("float {}", f.value()),
        Item::Value(Value::Boolean(b)) => format!("boolean {}", b.value()),
        Item::Value(Value::Datetime(d)) => format!("datetime {}", d.value()),
        Item::Value(Value::Array(_)) => "an array".into(),
        Item::ArrayOfTables(_) => "an array of tables".into(),
        _ => "a table".into(),
    }
}

fn expected(what: &str, item: &Item) -> String {
    format!("expected {what}, found {}", found(item))
}

fn string(item: &Item) -> Result<String, String> {
    item.as_str()
        .map(str::to_string)
        .ok_or_else(|| expected("a string", item))
}

fn probability(item: &Item) -> Result<f64, String> {
    let f = number(item)?;
    if (0.0..=1.0).contains(&f) {
        Ok(f)
    } else {
        Err(format!("must be between 0.0 and 1.0, found {f}"))
    }
}

fn unsigned(item: &Item) -> Result<u64, String> {
    item.as_integer()
        .and_then(|i| u64::try_from(i).ok())
        .ok_or_else(|| expected("a non-negative integer", item))
}

fn number(item: &Item) -> Result<f64, String> {
    item.as_float()
        .or_else(|| item.as_integer().map(|i| i as f64))
        .ok_or_else(|| expected("a number", item))
}

fn boolean(item: &Item) -> Result<bool, String> {
    item.as_bool()
        .ok_or_else(|| expected("true or false", item))
}

fn strings(item: &Item) -> Result<Vec<String>, String> {
    let list = item
        .as_array()
        .ok_or_else(|| expected("an array of strings", item))?;
    list.iter()
        .map(|v| v.as_str().map(str::to_string))
        .collect::<Option<_>>()
        .ok_or_else(|| expected("an array of strings", item))
}

fn patterns(item: &Item) -> Result<Vec<String>, String> {
    let list = strings(item)?;
    match list
        .iter()
        .find(|p| p.trim().is_empty() || p.contains("***"))
    {
        Some(bad) => Err(format!("'{bad}' is not a topic pattern")),
        None => Ok(list),
    }
}

fn duration(item: &Item) -> Result<Duration, String> {
    caravan::parse_duration(&string(item)?).map_err(|e| e.to_string())
}

fn positive_duration(item: &Item) -> Result<Duration, String> {
    let d = duration(item)?;
    if d.is_zero() {
        return Err("must be greater than zero".into());
    }
    Ok(d)
}

fn restart(item: &Item) -> Result<Restart, String> {
    let text = string(item)?;
    text.parse::<Restart>()
        .map_err(|e| match suggest::nearest(&text, Restart::NAMES) {
            Some(near) => format!("'{text}' is not a restart policy; did you mean '{near}'?"),
            None => e,
        })
}

fn env(item: &Item) -> Result<BTreeMap<String, String>, String> {
    let table = item
        .as_table_like()
        .ok_or_else(|| expected("a table of strings", item))?;
    let mut env = BTreeMap::new();
    for (key, value) in table.iter() {
        if key.is_empty() || key.contains(['=', '\0']) {
            return Err(format!("'{key}' is not an environment variable name"));
        }
        let value = value
            .as_str()
            .ok_or_else(|| format!("value of '{key}': {}", expected("a string", value)))?;
        env.insert(key.to_string(), value.to_string());
    }
    Ok(env)
}

fn params(item: &Item) -> Result<serde_json::Value, String> {
    if !item.is_table_like() {
        return Err(expected("a table", item));
    }
    to_json(item, "params")
}

/// Params are handed to nodes as JSON; TOML datetimes become strings.
fn to_json(item: &Item, at: &str) -> Result<serde_json::Value, String> {
    use serde_json::Value as J;
    let table = |t: &dyn TableLike| -> Result<J, String> {
        t.iter()
            .map(|(k, v)| Ok((k.to_string(), to_json(v, &format!("{at}.{k}"))?)))
            .collect::<Result<serde_json::Map<_, _>, String>>()
            .map(J::Object)
    };
    Ok(match item {
        Item::None => J::Null,
        Item::Table(t) => table(t)?,
        Item::ArrayOfTables(a) => J::Array(a.iter().map(|t| table(t)).collect::<Result<_, _>>()?),
        Item::Value(v) => match v {
            Value::String(s) => J::String(s.value().clone()),
            Value::Integer(i) => J::from(*i.value()),
            Value::Float(f) => serde_json::Number::from_f64(*f.value())
                .map(J::Number)
                .ok_or_else(|| format!("{at}: {} cannot be passed as a parameter", f.value()))?,
            Value::Boolean(b) => J::Bool(*b.value()),
            Value::Datetime(d) => J::String(d.value().to_string()),
            Value::Array(a) => J::Array(
                a.iter()
                    .map(|v| to_json(&Item::Value(v.clone()), at))
                    .collect::<Result<_, _>>()?,
            ),
            Value::InlineTable(t) => table(t)?,
        },
    })
}

/// Parses a bandwidth like `"54Mbit"`, `"500kbit"` or `"1Gbit"` into bits per second.
pub fn parse_bandwidth(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let scale = match unit.trim().to_ascii_lowercase().as_str() {
        "bit" => 1.0,
        "kbit" => 1e3,
        "mbit" => 1e6,
        "gbit" => 1e9,
        _ => f64::NAN,
    };
    let bps = number
        .parse::<f64>()
        .map(|n| (n * scale).round())
        .unwrap_or(f64::NAN);
    if bps.is_finite() && bps >= 1.0 && bps < u64::MAX as f64 {
        Ok(bps as u64)
    } else {
        Err(format!(
            "'{text}' is not a bandwidth; write a number and a unit: bit, kbit, Mbit or Gbit (\"54Mbit\")"
        ))
    }
}

fn is_process_name(name: &str) -> bool {
    !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

fn is_executable(path: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    path.metadata()
        .is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

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
    fn temp_dir() -> PathBuf {
        static NEXT: AtomicUsize = AtomicUsize::new(0);
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("caravan-launch-{}-{n}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn resolve(name: &str) -> Option<PathBuf> {
        ["caravan-physics", "planner", "sleep"]
            .contains(&name)
            .then(|| PathBuf::from("/usr/bin").join(name))
    }

    fn load_text(text: &str, sets: &[&str]) -> Result<LaunchFile, LaunchError> {
        let path = temp_dir().join("launch.toml");
        std::fs::write(&path, text).unwrap();
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        load(&path, &sets, &resolve)
    }

    /// The error's lines, with the temp file's path replaced by FILE.
    fn errors(text: &str, sets: &[&str]) -> Vec<String> {
        let path = temp_dir().join("launch.toml");
        std::fs::write(&path, text).unwrap();
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        let err = load(&path, &sets, &resolve).expect_err("should be rejected");
        assert_eq!(err.exit_code(), 2);
        let shown = err.to_string().replace(&path.display().to_string(), "FILE");
        shown.lines().map(str::to_string).collect()
    }

    fn edited(from: &str, to: &str) -> String {
        assert!(BASE.contains(from), "{from}");
        BASE.replacen(from, to, 1)
    }

    fn assert_error(lines: &[String], expected: &str) {
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
        assert!(
            lines[0].starts_with("FILE:13: key 'proces': unknown key; did you mean 'process'?")
        );
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
        assert!(lines[0].starts_with(
            "FILE:15: process 'physics', key 'exec': unknown executable './bin/physics'"
        ));
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
        assert!(
            lines[0].starts_with("FILE:11: link #1, key 'latency': '6 parsecs' is not a duration")
        );
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
    fn launch_bad_link_profiles_are_named() {
        let text = edited(
            "latency = \"6ms\"\n",
            "latency = \"6ms\"\ndistribution = \"gauss\"\nspike = [\"100ms\", \"50ms\"]\nspike_probability = 2.0\n",
        );
        let lines = errors(&text, &[]);
        assert_error(
            &lines,
            "FILE:12: link #1, key 'distribution': 'gauss' is not a jitter distribution; use uniform, normal or exponential",
        );
        assert_error(
            &lines,
            "FILE:13: link #1, key 'spike': the spike's minimum exceeds its maximum",
        );
        assert_error(
            &lines,
            "FILE:14: link #1, key 'spike_probability': must be between 0.0 and 1.0, found 2",
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
                "--set process.physics.colour=red: process 'physics', key 'colour': unknown key; expected one of: name, exec, args, host, rate, on, params, restart, restart_backoff, max_restarts, required, env"
            ]
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
        // Without [hosts], any host goes.
        let text = BASE.replace("[hosts.sim]\n[hosts.rpi-0]\ncpu_slowdown = 12.0\n", "");
        let text = text.replace(
            "[[links]]\nbetween = [\"rpi-*\", \"sim\"]\nlatency = \"6ms\"\n",
            "",
        );
        assert_eq!(load_text(&text, &[]).unwrap().processes[0].host, "sim");
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
    fn launch_link_pattern_matching_nothing() {
        let lines = errors(&edited("\"rpi-*\", \"sim\"", "\"rpi-*\", \"simm\""), &[]);
        assert_eq!(
            lines,
            [
                "FILE:10: link #1, key 'between': pattern 'simm' matches no declared host; did you mean 'sim'?"
            ]
        );
        let lines = errors(&edited("[\"rpi-*\", \"sim\"]", "[\"rpi-*\"]"), &[]);
        assert_error(
            &lines,
            "FILE:10: link #1, key 'between': expected exactly two host patterns, found 1",
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
            "FILE:7: host 'rpi-0', key 'cpu_slowdown': must be at least 1.0 (1.0 = as fast as this machine), found 0.5",
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

    #[test]
    fn launch_bandwidths() {
        assert_eq!(parse_bandwidth("54Mbit"), Ok(54_000_000));
        assert_eq!(parse_bandwidth("10mbit"), Ok(10_000_000));
        assert_eq!(parse_bandwidth("1Gbit"), Ok(1_000_000_000));
        assert_eq!(parse_bandwidth("500kbit"), Ok(500_000));
        assert_eq!(parse_bandwidth("1.5 Mbit"), Ok(1_500_000));
        for bad in ["", "54", "54MB", "0Mbit", "fast"] {
            assert!(parse_bandwidth(bad).is_err(), "{bad}");
        }
    }
}
