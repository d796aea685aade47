//! The sections of a launch file: `[group]`, `[hosts]`, `[[links]]`, `[[process]]` and
//! `[[report]]`, each read into its typed model with every problem recorded.

use super::check::{Checker, Scope};
use super::convert::*;
use super::model::*;
use super::overrides::Seg;
use super::suggest;
use caravan::ClockMode;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use std::time::Duration;
use toml_edit::Item;

/// The keys a launch file may have at the top; `include` is resolved before checking.
pub const TOP_KEYS: &[&str] = &[
    "args", "include", "group", "hosts", "links", "process", "report",
];
pub(crate) const GROUP_KEYS: &[&str] = &[
    "name",
    "clock",
    "duration",
    "seed",
    "tick",
    "overlap",
    "batch",
    "record",
    "grace",
    "step_timeout",
    "join_timeout",
    "host_lease",
    "spin",
];
pub(crate) const HOST_KEYS: &[&str] = &[
    "cpu_slowdown",
    "listen",
    "connect",
    "required",
    "clock",
    "tls",
];
pub(crate) const TLS_KEYS: &[&str] = &["ca", "certificate", "key"];
pub(crate) const LINK_KEYS: &[&str] = &[
    "between",
    "latency",
    "jitter",
    "distribution",
    "loss",
    "spike_probability",
    "spike",
    "bandwidth",
];
pub(crate) const PROCESS_KEYS: &[&str] = &[
    "name",
    "exec",
    "args",
    "host",
    "rate",
    "on",
    "spin",
    "params",
    "restart",
    "restart_backoff",
    "max_restarts",
    "required",
    "ends_group",
    "env",
    "check",
    "container",
];
pub(crate) const REPORT_KEYS: &[&str] = &["exec", "params", "timeout"];

impl Checker<'_> {
    pub fn group(&mut self, root: &Scope) -> GroupSpec {
        let mut group = GroupSpec {
            name: String::new(),
            clock: ClockMode::Lockstep,
            duration: None,
            seed: 0,
            tick: GroupSpec::DEFAULT_TICK,
            overlap: true,
            batch: true,
            record: Vec::new(),
            grace: GroupSpec::DEFAULT_GRACE,
            step_timeout: GroupSpec::DEFAULT_STEP_TIMEOUT,
            join_timeout: GroupSpec::DEFAULT_JOIN_TIMEOUT,
            host_lease: GroupSpec::DEFAULT_HOST_LEASE,
            spin: Duration::ZERO,
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
        group.overlap = self.get(&s, "overlap", boolean).unwrap_or(true);
        group.batch = self.get(&s, "batch", boolean).unwrap_or(true);
        group.record = self.get(&s, "record", patterns).unwrap_or_default();
        group.grace = self
            .get(&s, "grace", duration)
            .unwrap_or(GroupSpec::DEFAULT_GRACE);
        group.step_timeout = self
            .get(&s, "step_timeout", positive_duration)
            .unwrap_or(GroupSpec::DEFAULT_STEP_TIMEOUT);
        group.join_timeout = self
            .get(&s, "join_timeout", positive_duration)
            .unwrap_or(GroupSpec::DEFAULT_JOIN_TIMEOUT);
        group.host_lease = self
            .get(&s, "host_lease", host_lease)
            .unwrap_or(GroupSpec::DEFAULT_HOST_LEASE);
        group.spin = self.get(&s, "spin", spin).unwrap_or_default();
        group
    }

    pub fn hosts(&mut self, root: &Scope) -> BTreeMap<String, HostSpec> {
        let mut hosts = BTreeMap::new();
        let mut hosts_with_tls = 0;
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
                // A step's emulated compute time is its real one times this, in ns.
                if (1.0..=1e6).contains(&f) {
                    Ok(f)
                } else {
                    Err(format!(
                        "must be 1.0 to 1e6 (1.0 = as fast as this machine), found {f}"
                    ))
                }
            });
            let listen = self.get(&h, "listen", endpoints).unwrap_or_default();
            let connect = self.get(&h, "connect", endpoints).unwrap_or_default();
            let required = self.get(&h, "required", boolean).unwrap_or(true);
            let clock = self.get(&h, "clock", boolean).unwrap_or(false);
            // A tls table with a problem of its own (named already) still counts as given, so
            // what depends on it is not refused as well.
            let has_tls = h.table.get("tls").is_some();
            let tls = self.tls(&h, name);
            if has_tls {
                hosts_with_tls += 1;
            }
            for (key, list) in [("listen", &listen), ("connect", &connect)] {
                let secure = list.iter().filter(|e| e.starts_with("quic/")).count();
                if has_tls && secure < list.len() {
                    let msg = "this host has a tls table: its endpoints must be quic/ADDRESS:PORT";
                    self.key_problem(&h, key, msg.to_string());
                } else if !has_tls && secure > 0 {
                    let msg = format!(
                        "a quic/ endpoint needs a [hosts.{name}.tls] table with ca, certificate and key"
                    );
                    self.key_problem(&h, key, msg);
                }
            }
            if clock && let Some(other) = hosts.iter().find(|(_, h): &(_, &HostSpec)| h.clock) {
                let msg = format!(
                    "host '{}' already has clock = true; one host owns simulated time",
                    other.0
                );
                self.key_problem(&h, "clock", msg);
            }
            hosts.insert(
                name.to_string(),
                HostSpec {
                    cpu_slowdown,
                    listen,
                    connect,
                    required,
                    tls,
                    clock,
                },
            );
        }
        if hosts_with_tls > 0 && hosts_with_tls < hosts.len() {
            let msg = "some hosts have a tls table and some do not: hosts without one could not connect to those with one; give every host a tls table, or none";
            self.scope_problem(&s, msg);
        }
        hosts
    }

    /// A host's `tls` table. Its files need exist only on the host itself (a private key
    /// never leaves its machine): those missing are kept in [`TlsSpec::missing`] for
    /// `--host` to report.
    fn tls(&mut self, h: &Scope, name: &str) -> Option<TlsSpec> {
        let t = self.table(h, "tls", format!("host '{name}' tls"), Some(TLS_KEYS))?;
        let dir = self.origins.entry(&t.path).0.abs_dir.clone();
        let mut missing = Vec::new();
        let mut file = |key: &str| {
            let given = self.required(&t, key, string)?;
            let path = dir.join(&given);
            if !path.is_file() {
                let msg = format!("'{given}' is not a file ({})", path.display());
                missing.push(self.deferred_problem(&t, key, msg).to_string());
            }
            Some(path)
        };
        let (ca, certificate, key) = (file("ca"), file("certificate"), file("key"));
        Some(TlsSpec {
            ca: ca?,
            certificate: certificate?,
            key: key?,
            missing,
        })
    }

    pub fn links(&mut self, root: &Scope, hosts: &BTreeMap<String, HostSpec>) -> Vec<LinkSpec> {
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

    pub fn processes(
        &mut self,
        root: &Scope,
        hosts: &BTreeMap<String, HostSpec>,
    ) -> Vec<ProcessSpec> {
        let entries = self.list(root, "process");
        if entries.is_empty() && root.get("process").is_none() {
            self.scope_problem(root, "no [[process]] entries; a group needs at least one");
        }
        let mut first_use: HashMap<String, Vec<Seg>> = HashMap::new();
        let mut containers = super::container::Containers::default();
        let mut processes = Vec::new();
        for (i, table) in entries {
            let mut label = match table.get("name").and_then(Item::as_str) {
                Some(name) => format!("process '{name}'"),
                None => format!("process #{}", i + 1),
            };
            let mut path = root.at("process");
            path.push(Seg::Index(i));
            let (source, note) = self.origins.entry(&path);
            if let Some(note) = note {
                label = format!("{label} ({note})");
            }
            let s = self.open(table, root.at("process"), i, label, PROCESS_KEYS);
            let name = self.required(&s, "name", string).unwrap_or_default();
            let named = table.get("name").is_some_and(Item::is_str);
            if let Some(first) = first_use.get(&name) {
                // Name the other file only when it is another one.
                let place = self.origins.place(first);
                let at = match place.line {
                    Some(l) if place.rank == source.rank => format!(" (line {l})"),
                    Some(_) => format!(" ({})", place.location),
                    None => String::new(),
                };
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
                    format!(
                        "'{name}' must be 1 to {MAX_PROCESS_NAME} letters, digits, '_' and '-'"
                    ),
                );
            }
            if named && containers.has(&name) {
                let what = format!("'{name}' is already the name of a container");
                self.key_problem(&s, "name", what);
            }
            let mut process = self.process(&s, name, hosts, &source.dir);
            process.launch_dir = source.abs_dir.clone();
            self.container(&s, &process, |n| first_use.contains_key(n), &mut containers);
            processes.push(process);
        }
        processes
    }

    pub fn process(
        &mut self,
        s: &Scope,
        name: String,
        hosts: &BTreeMap<String, HostSpec>,
        dir: &Path,
    ) -> ProcessSpec {
        let exec = self.exec(s, dir);
        let host = self.get(s, "host", string);
        if let Some(h) = &host
            && hosts.is_empty()
            && h != ProcessSpec::DEFAULT_HOST
        {
            self.key_problem(
                s,
                "host",
                format!(
                    "host '{h}' is not declared: the file has no [hosts] table; declare it there, or leave 'host' out to run on this machine"
                ),
            );
        } else if let Some(h) = &host
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
            // One topic, by its name (a pattern such as `demo/*` steps nothing).
            caravan::pattern::check_topic_name(&topic)?;
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
            spin: self.get(s, "spin", spin),
            params: self.params(s),
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
            ends_group: self.get(s, "ends_group", boolean).unwrap_or(false),
            env: self.get(s, "env", env).unwrap_or_default(),
            check: self.get(s, "check", boolean),
            container: self.get(s, "container", string),
            launch_dir: dir.to_path_buf(),
        }
    }

    pub fn reports(&mut self, root: &Scope) -> Vec<ReportSpec> {
        let mut reports = Vec::new();
        for (i, table) in self.list(root, "report") {
            let label = format!("report #{}", i + 1);
            let s = self.open(table, root.at("report"), i, label, REPORT_KEYS);
            let (source, _) = self.origins.entry(&s.path);
            let exec = self.exec(&s, &source.dir);
            let timeout = self.get(&s, "timeout", |item| {
                let d = duration(item)?;
                if d.is_zero() || d > ReportSpec::MAX_TIMEOUT {
                    return Err(format!(
                        "expected a time limit above 0 and at most {} h",
                        ReportSpec::MAX_TIMEOUT.as_secs() / 3600
                    ));
                }
                Ok(d)
            });
            reports.push(ReportSpec {
                exec: exec.unwrap_or(Exec::Command(Vec::new())),
                params: self.params(&s),
                timeout: timeout.unwrap_or(ReportSpec::DEFAULT_TIMEOUT),
                launch_dir: source.abs_dir.clone(),
            });
        }
        reports
    }

    /// Splits `exec` like a shell would and checks that its program exists; a path is
    /// relative to `dir`, the directory of the file that wrote the entry.
    pub fn exec(&mut self, s: &Scope, dir: &Path) -> Option<Exec> {
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
