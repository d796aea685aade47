//! The checker: reads typed values out of the resolved document and records every problem
//! with where it was written (an override, or a file and line found through [`Origins`]).

use super::convert::found;
use super::overrides::{Applied, Seg};
use super::problem::Problem;
use super::source::Origins;
use super::suggest;
use std::fmt;
use std::path::PathBuf;
use toml_edit::{Item, TableLike, Value};

/// A table being validated: where it is, and how messages name it ("process 'physics'").
pub struct Scope<'d> {
    pub table: &'d dyn TableLike,
    pub path: Vec<Seg>,
    pub label: String,
}

impl<'d> Scope<'d> {
    pub fn root(table: &'d dyn TableLike) -> Self {
        Scope {
            table,
            path: Vec::new(),
            label: String::new(),
        }
    }

    pub fn at(&self, key: &str) -> Vec<Seg> {
        let mut path = self.path.clone();
        path.push(Seg::Key(key.to_string()));
        path
    }

    pub fn get(&self, key: &str) -> Option<&'d Item> {
        self.table.get(key)
    }
}

pub struct Checker<'a> {
    pub origins: &'a Origins,
    /// Command-line overrides that were applied; they take the blame for what they set.
    pub applied: &'a [Applied],
    /// Paths whose further problems are not reported (an unresolved reference was).
    pub silenced: &'a [Vec<Seg>],
    pub resolve_exec: &'a dyn Fn(&str) -> Option<PathBuf>,
    pub problems: Vec<Problem>,
}

impl<'a> Checker<'a> {
    pub fn new(
        origins: &'a Origins,
        applied: &'a [Applied],
        silenced: &'a [Vec<Seg>],
        resolve_exec: &'a dyn Fn(&str) -> Option<PathBuf>,
    ) -> Self {
        Checker {
            origins,
            applied,
            silenced,
            resolve_exec,
            problems: Vec::new(),
        }
    }

    // ---- reporting ----

    /// Records a problem at `path`: blamed on the override that set it, else on where it was
    /// written.
    pub fn problem(&mut self, path: &[Seg], message: String) {
        if self.silenced.iter().any(|s| path.starts_with(s)) {
            return;
        }
        let problem = self.locate(path, message);
        self.problems.push(problem);
    }

    /// A problem at `key` of `s` that is not reported now but kept for later (a file that
    /// only one host must have), placed as [`Checker::problem`] would place it.
    pub fn deferred_problem(&self, s: &Scope, key: &str, message: impl fmt::Display) -> Problem {
        self.locate(&s.at(key), format!("{}, key '{key}': {message}", s.label))
    }

    fn locate(&self, path: &[Seg], message: String) -> Problem {
        let blamed = self
            .applied
            .iter()
            .rev()
            .find(|a| path.starts_with(&a.path));
        match blamed {
            Some(a) => Problem {
                location: format!("--set {}", a.text),
                line: None,
                rank: 0,
                message,
            },
            None => {
                let place = self.origins.place(path);
                Problem {
                    location: place.location,
                    line: place.line,
                    rank: place.rank,
                    message: message + &self.arguments_behind(path),
                }
            }
        }
    }

    /// ` (from $(arg NAME), set by --set args.NAME=…)` for each argument set on the command
    /// line that the value at `path` was written with: the line names the reference, the
    /// `--set` the value.
    fn arguments_behind(&self, path: &[Seg]) -> String {
        let Some(written) = self.origins.written(path) else {
            return String::new();
        };
        let mut notes = String::new();
        for a in self.applied {
            if let [Seg::Key(args), Seg::Key(name)] = a.path.as_slice()
                && args == "args"
                && written.contains(&format!("$(arg {name})"))
            {
                notes += &format!(" (from $(arg {name}), set by --set {})", a.text);
            }
        }
        notes
    }

    pub fn key_problem(&mut self, s: &Scope, key: &str, message: impl fmt::Display) {
        self.problem_below(s, key, &[], message);
    }

    /// A problem at `below` inside the value of `key` (a param deep in `params`), named by key.
    pub fn problem_below(
        &mut self,
        s: &Scope,
        key: &str,
        below: &[Seg],
        message: impl fmt::Display,
    ) {
        let what = if s.label.is_empty() {
            format!("key '{key}': {message}")
        } else {
            format!("{}, key '{key}': {message}", s.label)
        };
        let mut at = s.at(key);
        at.extend_from_slice(below);
        self.problem(&at, what);
    }

    /// A process's or report's `params` as JSON (an empty object when absent or wrong, the
    /// latter reported at the value that cannot be passed).
    pub fn params(&mut self, s: &Scope) -> serde_json::Value {
        let empty = || serde_json::Value::Object(Default::default());
        let Some(item) = s.get("params") else {
            return empty();
        };
        super::convert::params(item).unwrap_or_else(|e| {
            self.problem_below(s, "params", &e.below, e.message);
            empty()
        })
    }

    pub fn scope_problem(&mut self, s: &Scope, message: impl fmt::Display) {
        let label = if s.label.is_empty() { "file" } else { &s.label };
        self.problem(&s.path, format!("{label}: {message}"));
    }

    // ---- reading values ----

    pub fn unknown_keys(&mut self, s: &Scope, allowed: &[&str]) {
        for (key, _) in s.table.iter() {
            if !allowed.contains(&key) {
                let hint = suggest::hint(key, allowed);
                self.key_problem(s, key, format!("unknown key{hint}"));
            }
        }
    }

    /// The value of `key` converted, or `None` when absent or wrong (the latter reported).
    pub fn get<T>(
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

    pub fn required<T>(
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
    pub fn table<'d>(
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
    pub fn list<'d>(&mut self, parent: &Scope<'d>, key: &str) -> Vec<(usize, &'d dyn TableLike)> {
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

    /// A scope for entry `index` of the list at `path`, checking its keys against `allowed`.
    pub fn open<'d>(
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
}
