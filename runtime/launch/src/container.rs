//! The `container` key of a `[[process]]`: nodes of one program that run in one process
//! (see `caravan::container`). Its members are one process to the launcher, so they must
//! agree on everything that starts, places or restarts a process.

use super::check::{Checker, Scope};
use super::convert::{MAX_PROCESS_NAME, is_process_name};
use super::model::{Exec, ProcessSpec};
use std::collections::BTreeMap;

/// Each container's first member, by the container's name.
#[derive(Default)]
pub struct Containers {
    first: BTreeMap<String, ProcessSpec>,
}

impl Containers {
    /// Whether `name` names a container seen so far.
    pub fn has(&self, name: &str) -> bool {
        self.first.contains_key(name)
    }
}

/// The first key whose value differs between two members of one container.
fn differing_key(a: &ProcessSpec, b: &ProcessSpec) -> Option<&'static str> {
    let keys: [(&str, bool); 8] = [
        ("exec", a.exec == b.exec),
        ("args", a.args == b.args),
        ("host", a.host == b.host),
        ("env", a.env == b.env),
        ("restart", a.restart == b.restart),
        ("restart_backoff", a.restart_backoff == b.restart_backoff),
        ("max_restarts", a.max_restarts == b.max_restarts),
        ("check", a.check == b.check),
    ];
    keys.into_iter().find(|(_, same)| !same).map(|(key, _)| key)
}

/// Whether `exec` starts a Python agent, which runs a process of its own.
fn is_python(exec: &Exec) -> bool {
    let program = match exec {
        Exec::Workspace(name) => name.as_str(),
        Exec::Command(words) => words.first().map_or("", String::as_str),
    };
    program.rsplit('/').next() == Some("caravan-python")
}

impl Checker<'_> {
    /// Checks process `p`'s `container` (read from `s`) against the processes and containers
    /// before it: `is_process` tells whether a name is an earlier process's.
    pub fn container(
        &mut self,
        s: &Scope,
        p: &ProcessSpec,
        is_process: impl Fn(&str) -> bool,
        seen: &mut Containers,
    ) {
        let Some(name) = &p.container else { return };
        if !is_process_name(name) {
            let what =
                format!("'{name}' must be 1 to {MAX_PROCESS_NAME} letters, digits, '_' and '-'");
            return self.key_problem(s, "container", what);
        }
        if name == &p.name || is_process(name) {
            let what = format!(
                "'{name}' is the name of a process; a container needs a name of its own (it names the container's process and log)"
            );
            return self.key_problem(s, "container", what);
        }
        if is_python(&p.exec) {
            let what = "a container runs nodes built with caravan::node_main (Rust); a Python agent runs a process of its own";
            return self.key_problem(s, "container", what);
        }
        match seen.first.get(name) {
            None => {
                seen.first.insert(name.clone(), p.clone());
            }
            Some(first) => {
                if let Some(key) = differing_key(first, p) {
                    let what = format!(
                        "'{}' and '{}' are in container '{name}', one process, so their '{key}' must be the same",
                        first.name, p.name
                    );
                    self.key_problem(s, key_or_container(s, key), what);
                }
            }
        }
    }
}

/// Blame the differing key where this entry wrote it, else its `container`.
fn key_or_container<'k>(s: &Scope, key: &'k str) -> &'k str {
    if s.get(key).is_some() {
        key
    } else {
        "container"
    }
}
