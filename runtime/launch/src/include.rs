//! `[[include]]`: another launch file, resolved on its own (its `[args]` set by `args`, its own
//! includes), changed by `set` like `--set`, then merged into the including file: `[group]`
//! keys and `[hosts]` of the including file win key by key (a later include over an earlier
//! one), and `[[links]]`, `[[process]]` and `[[report]]` entries come first, in include order.

use super::args;
use super::check::{Checker, Scope};
use super::convert::{expected, string, strings};
use super::overrides::{self, Applied, Seg};
use super::problem::Problem;
use super::sections::TOP_KEYS;
use super::source::{Origin, Origins, ReadFailure, Source, moved};
use super::suggest;
use super::template;
use std::path::PathBuf;
use std::rc::Rc;
use toml_edit::{ArrayOfTables, DocumentMut, Item, Table, TableLike, Value};

const INCLUDE_KEYS: &[&str] = &["file", "args", "set"];
/// The sections whose entries are appended.
const LISTS: [&str; 3] = ["links", "process", "report"];

/// What resolving one file produces.
pub struct Resolved {
    pub doc: DocumentMut,
    pub origins: Origins,
    /// Paths whose problems are not reported (an unresolved reference already was).
    pub silenced: Vec<Vec<Seg>>,
    /// Whether templates or includes reshaped the document (then it is tidied when written).
    pub rebuilt: bool,
}

/// State shared while resolving a file and its includes.
pub struct Ctx<'a> {
    pub problems: Vec<Problem>,
    /// The rank the next file read gets.
    pub next_rank: usize,
    pub resolve_exec: &'a dyn Fn(&str) -> Option<PathBuf>,
    /// The files being resolved, outermost first (canonical path, as shown), to catch cycles.
    pub chain: Vec<(PathBuf, String)>,
    /// An included file could not be used, so the merged file lacks parts: what else is wrong
    /// with it would mostly be echoes.
    pub incomplete: bool,
}

/// Resolves one file on its own: its arguments (already set in `doc`), its templates, its
/// includes. `blame` are the overrides already applied to `doc`.
pub fn resolve_file(
    ctx: &mut Ctx,
    source: Rc<Source>,
    mut doc: DocumentMut,
    blame: &[Applied],
) -> Resolved {
    let written = Origins::new(&source);
    let report = |ctx: &mut Ctx, problems: Vec<(Vec<Seg>, String)>| {
        let mut check = Checker::new(&written, blame, &[], ctx.resolve_exec);
        for (path, message) in problems {
            check.problem(&path, message);
        }
        ctx.problems.extend(check.problems);
    };
    let mut silenced = Vec::new();
    let mut problems = Vec::new();
    for u in args::substitute(&mut doc) {
        if !u.quiet {
            problems.push((u.path.clone(), u.message));
        }
        silenced.push(u.path);
    }
    report(ctx, std::mem::take(&mut problems));
    let entries = template::expand(&mut doc, &source, &mut |path, message| {
        problems.push((path, message));
    });
    report(ctx, problems);
    let mut origins = Origins::new(&source);
    let rebuilt = entries.is_some();
    if let Some(entries) = entries {
        let process = Seg::Key("process".into());
        let mut kept: Vec<Vec<Seg>> = silenced
            .iter()
            .filter(|p| p.first() != Some(&process))
            .cloned()
            .collect();
        for (k, e) in entries.into_iter().enumerate() {
            let from = [process.clone(), Seg::Index(e.from)];
            let to = [process.clone(), Seg::Index(k)];
            kept.extend(moved(&silenced, &from, &to));
            if e.failed {
                kept.push(to.to_vec());
            }
            origins.push(
                to.to_vec(),
                Origin::File {
                    source: source.clone(),
                    path: from.to_vec(),
                    note: e.note,
                },
            );
        }
        silenced = kept;
    }
    let own = Resolved {
        doc,
        origins,
        silenced,
        rebuilt,
    };
    include(ctx, &source, own, blame)
}

fn key(k: &str) -> Seg {
    Seg::Key(k.to_string())
}

/// Resolves the includes of `own` (the file `source`, its arguments and templates done) and
/// merges them into it.
pub fn include(
    ctx: &mut Ctx,
    source: &Rc<Source>,
    mut own: Resolved,
    blame: &[Applied],
) -> Resolved {
    let Some(item) = own.doc.remove("include") else {
        return own;
    };
    let mut holder = Table::new();
    holder.insert("include", item);
    let root = Scope::root(&holder);
    let resolve_exec = ctx.resolve_exec;
    let mut check = Checker::new(&own.origins, blame, &own.silenced, resolve_exec);
    let mut children = Vec::new();
    for (n, table) in check.list(&root, "include") {
        let file = table.get("file").and_then(Item::as_str);
        let label = match file {
            Some(f) => format!("include '{f}'"),
            None => format!("include #{}", n + 1),
        };
        let s = check.open(table, root.at("include"), n, label, INCLUDE_KEYS);
        let args = check.get(&s, "args", |i| {
            let t = i
                .as_table_like()
                .ok_or_else(|| expected("a table of argument values", i))?;
            Ok(t.iter()
                .map(|(k, v)| (k.to_string(), v.clone()))
                .collect::<Vec<_>>())
        });
        let sets = check.get(&s, "set", strings);
        let Some(file) = check.required(&s, "file", string) else {
            continue;
        };
        let path = source.dir.join(&file);
        let rank = ctx.next_rank;
        let child = match Source::read(&path, rank) {
            Ok(child) => Rc::new(child),
            Err(ReadFailure::Io(why)) => {
                let msg = format!("cannot read {}: {why}", path.display());
                check.key_problem(&s, "file", msg);
                ctx.incomplete = true;
                continue;
            }
            Err(ReadFailure::Syntax(location, line, message)) => {
                ctx.next_rank += 1;
                ctx.incomplete = true;
                ctx.problems.push(Problem {
                    location,
                    line: Some(line),
                    rank,
                    message,
                });
                continue;
            }
        };
        ctx.next_rank += 1;
        let canonical = std::fs::canonicalize(&path).unwrap_or_else(|_| path.clone());
        if let Some(start) = ctx.chain.iter().position(|(c, _)| *c == canonical) {
            let mut names: Vec<String> =
                ctx.chain[start..].iter().map(|(_, d)| d.clone()).collect();
            names.push(path.display().to_string());
            let msg = format!("include cycle: {}", names.join(" → "));
            check.key_problem(&s, "file", msg);
            ctx.incomplete = true;
            continue;
        }
        let mut doc = child.original.clone().into_mut();
        for (name, value) in args.into_iter().flatten() {
            if let Err(why) = set_arg(&mut doc, &name, value) {
                let mut at = s.at("args");
                at.push(key(&name));
                check.problem(
                    &at,
                    format!("{}, key 'args': {}: {why}", s.label, path.display()),
                );
            }
        }
        ctx.chain.push((canonical, path.display().to_string()));
        let mut resolved = resolve_file(ctx, child.clone(), doc, &[]);
        ctx.chain.pop();
        for (m, text) in sets.into_iter().flatten().enumerate() {
            let mut at = s.at("set");
            at.push(Seg::Index(m));
            let failed = if overrides::targets_args(&text) {
                Some(
                    "set applies to the resolved file; pass arguments with args = { … }"
                        .to_string(),
                )
            } else {
                let (applied, rejected) =
                    overrides::apply(&mut resolved.doc, std::slice::from_ref(&text));
                for a in applied {
                    let place = own.origins.place(&at);
                    resolved.origins.push(
                        a.path,
                        Origin::Set {
                            location: format!("{}: set {text}", place.location),
                            line: place.line.unwrap_or(0),
                            rank: place.rank,
                        },
                    );
                }
                rejected.into_iter().next().map(|r| r.message)
            };
            if let Some(why) = failed {
                check.problem(&at, format!("{}, set '{text}': {why}", s.label));
            }
        }
        children.push(resolved);
    }
    let problems = check.problems;
    ctx.problems.extend(problems);
    merge(ctx, source, own, children)
}

/// Sets argument `name` of an included file, which must declare it.
fn set_arg(doc: &mut toml_edit::DocumentMut, name: &str, value: Item) -> Result<(), String> {
    let Some(args) = doc
        .get_mut(super::overrides::ARGS_TABLE)
        .and_then(Item::as_table_like_mut)
    else {
        return Err(format!("declares no argument '{name}' (it has no [args])"));
    };
    let declared: Vec<String> = args.iter().map(|(k, _)| k.to_string()).collect();
    let Some(Item::Value(old)) = args.get_mut(name) else {
        let hint = suggest::did_you_mean(name, declared.iter().map(String::as_str));
        return Err(format!("declares no argument '{name}'{hint}"));
    };
    let Item::Value(mut value) = value else {
        return Err(format!(
            "the value of '{name}' must be a value, not a table"
        ));
    };
    *value.decor_mut() = old.decor().clone();
    *old = value;
    Ok(())
}

/// Merges the resolved `children` into `own`, keeping track of where everything came from.
fn merge(
    ctx: &mut Ctx,
    source: &Rc<Source>,
    mut own: Resolved,
    children: Vec<Resolved>,
) -> Resolved {
    if children.is_empty() {
        return own;
    }
    let mut m = Merged {
        origins: Origins::new(source),
        silenced: Vec::new(),
    };
    let own_keys: Vec<String> = own.doc.iter().map(|(k, _)| k.to_string()).collect();
    for k in &own_keys {
        if !LISTS.contains(&k.as_str()) {
            m.keep(&own, &[key(k)], &[key(k)]);
        }
    }
    for sec in LISTS {
        let mut tables = Vec::new();
        for child in &children {
            for (j, t) in entries(ctx, child, sec) {
                let to = [key(sec), Seg::Index(tables.len())];
                m.keep(child, &[key(sec), Seg::Index(j)], &to);
                tables.push(t);
            }
        }
        let mine = own
            .doc
            .get(sec)
            .map(|i| i.is_array_of_tables() || i.is_array());
        if tables.is_empty() || mine == Some(false) {
            // Nothing to append, or the file's own section is malformed: leave it be.
            if mine.is_some() {
                m.keep(&own, &[key(sec)], &[key(sec)]);
            }
            continue;
        }
        if let Some(item) = own.doc.remove(sec) {
            for (j, t) in as_tables(item).into_iter().enumerate() {
                let to = [key(sec), Seg::Index(tables.len())];
                m.keep(&own, &[key(sec), Seg::Index(j)], &to);
                match t {
                    Some(t) => tables.push(t),
                    // Left for the checker to report, at its own line.
                    None => tables.push(Table::new()),
                }
            }
        }
        own.doc.insert(
            sec,
            Item::ArrayOfTables(tables.into_iter().collect::<ArrayOfTables>()),
        );
    }
    // The including file wins, then later includes over earlier ones: fill in what is missing.
    for child in children.iter().rev() {
        for (k, _) in child.doc.iter() {
            match k {
                "group" => m.fill(ctx, &mut own, child, &[key(k)], 1),
                "hosts" => m.fill(ctx, &mut own, child, &[key(k)], 2),
                _ if LISTS.contains(&k) => {}
                // Its own arguments were used up resolving it.
                "args" => {}
                _ => {
                    let hint = suggest::hint(k, TOP_KEYS);
                    report(
                        ctx,
                        child,
                        &[key(k)],
                        format!("key '{k}': unknown key{hint}"),
                    );
                }
            }
        }
    }
    Resolved {
        doc: own.doc,
        origins: m.origins,
        silenced: m.silenced,
        rebuilt: true,
    }
}

struct Merged {
    origins: Origins,
    silenced: Vec<Vec<Seg>>,
}

impl Merged {
    /// Records that what stood at `from` in `r` now stands at `to`.
    fn keep(&mut self, r: &Resolved, from: &[Seg], to: &[Seg]) {
        self.origins.transplant(&r.origins, from, to);
        self.silenced.extend(moved(&r.silenced, from, to));
    }

    /// Fills `own` at `path` with what `child` has there and `own` lacks, key by key down to
    /// `depth` levels (group: 1, hosts: 2 — the host, then its keys).
    fn fill(
        &mut self,
        ctx: &mut Ctx,
        own: &mut Resolved,
        child: &Resolved,
        path: &[Seg],
        depth: usize,
    ) {
        let Some(theirs) = get(child.doc.as_table(), path) else {
            return;
        };
        let Some(mine) = get(own.doc.as_table(), path) else {
            let (Some((Seg::Key(last), parent)), theirs) = (path.split_last(), theirs.clone())
            else {
                return;
            };
            let target = if parent.is_empty() {
                Some(own.doc.as_table_mut() as &mut dyn TableLike)
            } else {
                get_mut(own.doc.as_table_mut(), parent).and_then(Item::as_table_like_mut)
            };
            if let Some(target) = target {
                target.insert(last, theirs);
                self.keep(child, path, path);
            }
            return;
        };
        if depth == 0 || !mine.is_table_like() {
            // The including file's value wins (a malformed one is the checker's to report).
            return;
        }
        let Some(theirs) = theirs.as_table_like() else {
            let found = super::convert::found(theirs);
            report(
                ctx,
                child,
                path,
                format!("{}: expected a table, found {found}", names(path)),
            );
            return;
        };
        let keys: Vec<String> = theirs.iter().map(|(k, _)| k.to_string()).collect();
        for k in keys {
            let mut at = path.to_vec();
            at.push(key(&k));
            self.fill(ctx, own, child, &at, depth - 1);
        }
    }
}

fn names(path: &[Seg]) -> String {
    let keys: Vec<&str> = path
        .iter()
        .filter_map(|s| match s {
            Seg::Key(k) => Some(k.as_str()),
            Seg::Index(_) => None,
        })
        .collect();
    keys.join(".")
}

fn get<'t>(table: &'t Table, path: &[Seg]) -> Option<&'t Item> {
    let (Seg::Key(first), rest) = path.split_first()? else {
        return None;
    };
    let mut item = table.get(first)?;
    for seg in rest {
        let Seg::Key(k) = seg else { return None };
        item = item.as_table_like()?.get(k)?;
    }
    Some(item)
}

fn get_mut<'t>(table: &'t mut Table, path: &[Seg]) -> Option<&'t mut Item> {
    let (first, rest) = path.split_first()?;
    let Seg::Key(k) = first else { return None };
    let mut item = table.get_mut(k)?;
    for seg in rest {
        let Seg::Key(k) = seg else { return None };
        item = item.as_table_like_mut()?.get_mut(k)?;
    }
    Some(item)
}

/// Records a problem at `path` of a resolved included file.
fn report(ctx: &mut Ctx, r: &Resolved, path: &[Seg], message: String) {
    let mut check = Checker::new(&r.origins, &[], &r.silenced, ctx.resolve_exec);
    check.problem(path, message);
    ctx.problems.extend(check.problems);
}

/// The tables of the list `sec` of an included file with their index; malformed parts are
/// reported there and left out.
fn entries(ctx: &mut Ctx, child: &Resolved, sec: &str) -> Vec<(usize, Table)> {
    let Some(item) = child.doc.get(sec) else {
        return Vec::new();
    };
    if !(item.is_array_of_tables() || item.is_array()) {
        let msg = format!(
            "key '{sec}': expected [[{sec}]] tables, found {}",
            super::convert::found(item)
        );
        report(ctx, child, &[key(sec)], msg);
        return Vec::new();
    }
    let mut out = Vec::new();
    for (j, t) in as_tables(item.clone()).into_iter().enumerate() {
        match t {
            Some(t) => out.push((j, t)),
            None => {
                let msg = format!("{sec} entry {}: expected a table", j + 1);
                report(ctx, child, &[key(sec), Seg::Index(j)], msg);
            }
        }
    }
    out
}

/// A list's entries as tables (`None`: not a table).
fn as_tables(item: Item) -> Vec<Option<Table>> {
    match item {
        Item::ArrayOfTables(a) => a.into_iter().map(Some).collect(),
        Item::Value(Value::Array(a)) => a
            .into_iter()
            .map(|v| match v {
                Value::InlineTable(t) => Some(t.into_table()),
                _ => None,
            })
            .collect(),
        _ => Vec::new(),
    }
}
