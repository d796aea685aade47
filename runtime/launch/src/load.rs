//! Reads a launch file and resolves it: `--set args.*`, arguments (which may use each other),
//! process templates, includes (each resolved the same way, then changed by its `set`, then
//! merged), the other `--set` overrides, and validation. Every problem found is collected,
//! with its file and line, so the user can fix them in one go; nothing is started on any.

use super::args;
use super::check::{Checker, Scope};
use super::include::{Ctx, resolve_file};
use super::model::*;
use super::overrides::{self, Seg};
pub use super::problem::{LaunchError, Problem};
use super::sections::TOP_KEYS;
use super::source::{ReadFailure, Source};
use std::path::{Path, PathBuf};
use std::rc::Rc;
use toml_edit::{DocumentMut, Item, Table};

/// Loads and validates `path` with `overrides` (`KEY=VALUE`) applied. `resolve_exec` finds a
/// bare program name (workspace binaries, then PATH).
#[cfg(test)]
pub fn load(
    path: &Path,
    overrides: &[String],
    resolve_exec: &dyn Fn(&str) -> Option<PathBuf>,
) -> Result<LaunchFile, LaunchError> {
    load_checked(path, overrides, resolve_exec, &|_| Vec::new())
}

/// [`load`], then `check_entries` on the valid file: the problems it returns (each process's
/// and report plugin's own check of its params and inputs) are reported at the entry's params
/// in the file, or at the override that set them, like every other problem.
pub fn load_checked(
    path: &Path,
    overrides: &[String],
    resolve_exec: &dyn Fn(&str) -> Option<PathBuf>,
    check_entries: &dyn Fn(&LaunchFile) -> Vec<EntryProblem>,
) -> Result<LaunchFile, LaunchError> {
    load_source(path, None, overrides, resolve_exec, check_entries)
}

/// [`load_checked`] of `text` (when given) as if it were the file at `path`.
pub fn load_source(
    path: &Path,
    text: Option<String>,
    overrides: &[String],
    resolve_exec: &dyn Fn(&str) -> Option<PathBuf>,
    check_entries: &dyn Fn(&LaunchFile) -> Vec<EntryProblem>,
) -> Result<LaunchFile, LaunchError> {
    let read = match text {
        Some(text) => Source::parse(path, text, 0),
        None => Source::read(path, 0),
    };
    let source = match read {
        Ok(s) => Rc::new(s),
        Err(ReadFailure::Io(reason)) => {
            return Err(LaunchError::Read {
                path: path.to_path_buf(),
                reason,
            });
        }
        Err(ReadFailure::Syntax(location, line, message)) => {
            return Err(LaunchError::Invalid(vec![Problem {
                location,
                line: Some(line),
                rank: 0,
                message,
            }]));
        }
    };
    // Arguments are set before anything uses them; the rest once includes are merged, so
    // they reach included processes and template repetitions by name.
    let (arg_sets, other_sets): (Vec<_>, Vec<_>) = overrides
        .iter()
        .enumerate()
        .partition(|(_, s)| overrides::targets_args(s));
    let texts = |sets: &[(usize, &String)]| -> Vec<String> {
        sets.iter().map(|(_, s)| (*s).clone()).collect()
    };
    let mut doc = source.original.clone().into_mut();
    let (mut applied, rejected_args) = overrides::apply(&mut doc, &texts(&arg_sets));
    let mut ctx = Ctx {
        problems: Vec::new(),
        next_rank: 1,
        resolve_exec,
        chain: vec![(
            std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf()),
            path.display().to_string(),
        )],
        incomplete: false,
    };
    let mut resolved = resolve_file(&mut ctx, source, doc, &applied);
    let args = args_table(&resolved.doc);
    let (applied_rest, rejected_rest) =
        overrides::apply_with(&mut resolved.doc, &texts(&other_sets), &|v| {
            args::expand_value(v, &args)
        });
    applied.extend(applied_rest);
    // Rejected overrides first, in command-line order.
    let mut rejected: Vec<(usize, Problem)> = Vec::new();
    let order = |text: &str, from: &[(usize, &String)]| {
        from.iter()
            .find(|(_, s)| s.as_str() == text)
            .map_or(0, |(i, _)| *i)
    };
    for r in rejected_args {
        rejected.push((order(&r.text, &arg_sets), rejected_problem(r)));
    }
    // With an included file missing, overrides of its parts fail only because of that.
    for r in rejected_rest.into_iter().filter(|_| !ctx.incomplete) {
        rejected.push((order(&r.text, &other_sets), rejected_problem(r)));
    }
    rejected.sort_by_key(|(i, _)| *i);

    let mut check = Checker::new(
        &resolved.origins,
        &applied,
        &resolved.silenced,
        resolve_exec,
    );
    let root = Scope::root(resolved.doc.as_table());
    check.unknown_keys(&root, TOP_KEYS);
    let group = check.group(&root);
    let hosts = check.hosts(&root);
    let links = check.links(&root, &hosts);
    let processes = check.processes(&root, &hosts);
    for (i, p) in processes.iter().enumerate() {
        let period = p.rate.as_deref().and_then(|r| caravan::parse_rate(r).ok());
        if group.clock == caravan::ClockMode::Lockstep
            && let Some(period) = period.filter(|&period| period < group.tick)
        {
            let mut at = root.at("process");
            at.extend([Seg::Index(i), Seg::Key("rate".into())]);
            check.problem(
                &at,
                format!(
                    "process '{}': a period of {period:?} is shorter than the group's tick ({:?}); a lockstep node steps at most once a tick",
                    p.name, group.tick
                ),
            );
        }
    }
    let reports = check.reports(&root);
    let mut problems: Vec<Problem> = rejected.into_iter().map(|(_, p)| p).collect();
    problems.extend(ctx.problems);
    if !ctx.incomplete {
        problems.extend(std::mem::take(&mut check.problems));
    }
    let mut lf = None;
    if problems.is_empty() {
        let file = LaunchFile {
            path: path.to_path_buf(),
            group,
            hosts,
            links,
            processes,
            reports,
            resolved_toml: String::new(),
            left_out: Default::default(),
        };
        for p in check_entries(&file) {
            let mut at = root.at(p.list.key());
            at.push(Seg::Index(p.index));
            at.push(Seg::Key("params".into()));
            at.extend(p.key.as_deref().map(key_path).unwrap_or_default());
            check.problem(&at, p.message);
        }
        problems.extend(check.problems);
        lf = Some(file);
    }
    match lf {
        Some(mut lf) if problems.is_empty() => {
            if resolved.rebuilt {
                tidy(&mut resolved.doc);
            }
            lf.resolved_toml = resolved.doc.to_string();
            Ok(lf)
        }
        _ => {
            problems.sort_by_key(|p| (p.rank, p.line.unwrap_or(0)));
            // A file included twice says the same twice.
            let mut seen = std::collections::HashSet::new();
            problems.retain(|p| seen.insert(p.to_string()));
            Err(LaunchError::Invalid(problems))
        }
    }
}

/// `a.b[2].c` as path segments.
fn key_path(key: &str) -> Vec<Seg> {
    let mut segs = Vec::new();
    for part in key.split('.') {
        let mut rest = part;
        if let Some(open) = rest.find('[') {
            segs.push(Seg::Key(rest[..open].to_string()));
            rest = &rest[open..];
            while let Some(close) = rest.find(']') {
                if let Ok(i) = rest[1..close].parse() {
                    segs.push(Seg::Index(i));
                }
                rest = &rest[close + 1..];
            }
        } else {
            segs.push(Seg::Key(rest.to_string()));
        }
    }
    segs
}

fn rejected_problem(r: overrides::Rejected) -> Problem {
    Problem {
        location: format!("--set {}", r.text),
        line: None,
        rank: 0,
        message: r.message,
    }
}

/// The `[args]` table of `doc` (empty when there is none).
fn args_table(doc: &DocumentMut) -> Table {
    match doc.get(args::TABLE) {
        Some(Item::Table(t)) => t.clone(),
        Some(Item::Value(toml_edit::Value::InlineTable(t))) => t.clone().into_table(),
        _ => Table::new(),
    }
}

/// Puts the sections of a reshaped document in the usual order and numbers its tables in
/// that order, so the resolved file reads like a hand-written one.
fn tidy(doc: &mut DocumentMut) {
    const ORDER: [&str; 6] = ["args", "group", "hosts", "links", "process", "report"];
    let root = doc.as_table_mut();
    let mut entries = Vec::new();
    let keys: Vec<String> = root.iter().map(|(k, _)| k.to_string()).collect();
    for k in keys {
        entries.extend(root.remove_entry(&k));
    }
    entries.sort_by_key(|(k, _)| {
        ORDER
            .iter()
            .position(|o| *o == k.get())
            .unwrap_or(ORDER.len())
    });
    for (k, item) in entries {
        root.insert_formatted(&k, item);
    }
    let mut next = 0;
    number_tables(root, &mut next);
}

fn number_tables(table: &mut Table, next: &mut isize) {
    table.set_position(*next);
    *next += 1;
    for (_, item) in table.iter_mut() {
        match item {
            Item::Table(t) => number_tables(t, next),
            Item::ArrayOfTables(a) => {
                for t in a.iter_mut() {
                    number_tables(t, next);
                }
            }
            _ => {}
        }
    }
}
