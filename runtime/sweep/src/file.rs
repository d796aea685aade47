//! Sweep files: a TOML file with a top-level `[sweep]` table naming a launch file, seeds,
//! common overrides and axes (plain ones over one key, named ones whose values are bundles of
//! overrides). Every problem is reported as `file:line: what` before anything runs.

use super::grid::{Axis, AxisValue};
use caravan_launch::overrides::parse_value;
use caravan_launch::suggest;
use std::path::{Path, PathBuf};
use toml_edit::{Document, Item, Key, TableLike, Value};

const TOP_KEYS: &[&str] = &["sweep"];
const SWEEP_KEYS: &[&str] = &["name", "launch", "seeds", "set", "jobs", "axis"];
const AXIS_KEYS: &[&str] = &["key", "name", "values"];

/// A parsed sweep file.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepFile {
    /// `name`, else the file's stem.
    pub name: String,
    /// The launch file, resolved against the sweep file's directory.
    pub launch: PathBuf,
    pub seeds: Option<Vec<u64>>,
    pub sets: Vec<String>,
    pub jobs: Option<usize>,
    pub axes: Vec<Axis>,
}

/// Whether `text` is a sweep file (TOML with a top-level `[sweep]` table) rather than a
/// launch file. Unparsable text is not: the launch loader then reports its syntax error.
pub fn is_sweep_file(text: &str) -> bool {
    Document::parse(text).is_ok_and(|d| d.get("sweep").is_some_and(Item::is_table_like))
}

/// Parses a sweep file; on error, every problem as `file:line: message`.
pub fn parse(path: &Path, text: &str) -> Result<SweepFile, Vec<String>> {
    let doc = Document::parse(text).map_err(|e| {
        let at = e.span().map_or(0, |s| s.start);
        vec![format!(
            "{}:{}: TOML syntax error: {}",
            path.display(),
            caravan_launch::source::line_at(text, at),
            e.message().trim()
        )]
    })?;
    let mut p = Parser {
        path,
        text,
        problems: Vec::new(),
    };
    p.unknown_keys(doc.as_table(), TOP_KEYS, "", 0);
    let Some((sweep_key, sweep)) = doc.as_table().get_key_value("sweep") else {
        return Err(vec![format!("{}: no [sweep] table", path.display())]);
    };
    let at = p.offset(sweep_key, sweep);
    let Some(sweep) = sweep.as_table_like() else {
        return Err(vec![format!(
            "{}:{}: 'sweep' must be a table",
            path.display(),
            caravan_launch::source::line_at(text, at)
        )]);
    };
    p.unknown_keys(sweep, SWEEP_KEYS, "[sweep] ", at);
    let file = p.sweep(sweep, at);
    match file {
        Some(f) if p.problems.is_empty() => Ok(f),
        _ => {
            p.problems.sort_by_key(|(line, _)| *line);
            Err(p.problems.into_iter().map(|(_, m)| m).collect())
        }
    }
}

struct Parser<'a> {
    path: &'a Path,
    text: &'a str,
    /// (line, message)
    problems: Vec<(usize, String)>,
}

impl Parser<'_> {
    /// Where `key` (or, failing that, its item) starts in the file.
    fn offset(&self, key: &Key, item: &Item) -> usize {
        key.span().or_else(|| item.span()).map_or(0, |s| s.start)
    }

    /// `file:line` of `offset`.
    fn at(&self, offset: usize) -> String {
        let line = caravan_launch::source::line_at(self.text, offset);
        format!("{}:{line}", self.path.display())
    }

    fn problem(&mut self, offset: usize, message: String) {
        let line = caravan_launch::source::line_at(self.text, offset);
        self.problems
            .push((line, format!("{}:{line}: {message}", self.path.display())));
    }

    fn unknown_keys(&mut self, t: &dyn TableLike, allowed: &[&str], scope: &str, at: usize) {
        for (key, item) in t.iter() {
            if !allowed.contains(&key) {
                let k = t.key(key).expect("iterated key");
                let offset = k.span().or_else(|| item.span()).map_or(at, |s| s.start);
                let hint = suggest::hint(key, allowed);
                self.problem(offset, format!("{scope}key '{key}': unknown key{hint}"));
            }
        }
    }

    /// The value at `key` with its offset, if present.
    fn value<'t>(&self, t: &'t dyn TableLike, key: &str, at: usize) -> Option<(&'t Item, usize)> {
        let (k, item) = t.get_key_value(key)?;
        Some((
            item,
            k.span().or_else(|| item.span()).map_or(at, |s| s.start),
        ))
    }

    fn sweep(&mut self, t: &dyn TableLike, at: usize) -> Option<SweepFile> {
        let name = match self.value(t, "name", at) {
            Some((item, off)) => match item.as_str() {
                Some(s) if !s.trim().is_empty() => s.trim().to_string(),
                _ => {
                    self.problem(
                        off,
                        "[sweep] key 'name': expected a non-empty string".into(),
                    );
                    String::new()
                }
            },
            None => self
                .path
                .file_stem()
                .map_or("sweep".into(), |s| s.to_string_lossy().into_owned()),
        };
        let launch = match self.value(t, "launch", at) {
            Some((item, off)) => {
                match item.as_str() {
                    Some(s) if !s.is_empty() => Some(
                        self.path
                            .parent()
                            .filter(|p| !p.as_os_str().is_empty())
                            .map_or_else(|| PathBuf::from(s), |dir| dir.join(s)),
                    ),
                    _ => {
                        self.problem(off, "[sweep] key 'launch': expected a path (a string), relative to this file".into());
                        None
                    }
                }
            }
            None => {
                self.problem(at, "[sweep]: missing required key 'launch'".into());
                None
            }
        };
        if let Some(l) = &launch
            && !l.is_file()
            && let Some((_, off)) = self.value(t, "launch", at)
        {
            self.problem(
                off,
                format!("[sweep] key 'launch': no launch file at {}", l.display()),
            );
        }
        let seeds = self
            .value(t, "seeds", at)
            .and_then(|(item, off)| match seeds(item) {
                Ok(s) => Some(s),
                Err(e) => {
                    self.problem(off, format!("[sweep] key 'seeds': {e}"));
                    None
                }
            });
        let sets = match self.value(t, "set", at) {
            Some((item, off)) => self.strings(item, off, "[sweep] key 'set'"),
            None => Vec::new(),
        };
        let jobs = self
            .value(t, "jobs", at)
            .and_then(|(item, off)| match item.as_integer() {
                Some(n) if n >= 1 => Some(n as usize),
                _ => {
                    self.problem(
                        off,
                        "[sweep] key 'jobs': expected a whole number ≥ 1".into(),
                    );
                    None
                }
            });
        let mut axes: Vec<Axis> = Vec::new();
        if let Some((item, off)) = self.value(t, "axis", at) {
            match item {
                Item::ArrayOfTables(list) => {
                    for (i, axis) in list.iter().enumerate() {
                        let at = axis.span().map_or(off, |s| s.start);
                        if let Some(a) = self.axis(axis, i + 1, at) {
                            if axes.iter().any(|b| b.label == a.label) {
                                let what = format!(
                                    "[[sweep.axis]] #{}: axis '{}' given twice",
                                    i + 1,
                                    a.label
                                );
                                self.problem(at, what);
                            }
                            axes.push(a);
                        }
                    }
                }
                _ => self.problem(
                    off,
                    "[sweep] key 'axis': expected [[sweep.axis]] tables".into(),
                ),
            }
        }
        Some(SweepFile {
            name,
            launch: launch?,
            seeds,
            sets,
            jobs,
            axes,
        })
    }

    fn axis(&mut self, t: &dyn TableLike, number: usize, at: usize) -> Option<Axis> {
        let scope = format!("[[sweep.axis]] #{number}");
        self.unknown_keys(t, AXIS_KEYS, &format!("{scope}, "), at);
        let key = self.value(t, "key", at);
        let name = self.value(t, "name", at);
        let Some((values, voff)) = self.value(t, "values", at) else {
            self.problem(at, format!("{scope}: missing required key 'values'"));
            return None;
        };
        match (key, name) {
            (Some((k, off)), None) => {
                let Some(key) = label(k) else {
                    self.problem(
                        off,
                        format!(
                            "{scope}, key 'key': expected a --set key, e.g. \"args.localisation\""
                        ),
                    );
                    return None;
                };
                let Some(list) = values.as_array() else {
                    self.problem(
                        voff,
                        format!("{scope}, key 'values': expected a list of values, e.g. [1, 2]"),
                    );
                    return None;
                };
                let texts: Vec<String> = list.iter().map(set_text).collect();
                self.check_values(&scope, voff, &texts)?;
                let mut axis = Axis::plain(key, texts);
                // Labels show strings without quotes; the sets keep their TOML type.
                for (v, item) in axis.values.iter_mut().zip(list.iter()) {
                    v.label = item.as_str().map_or_else(|| bare(item), str::to_string);
                    v.origin = Some(self.at(item.span().map_or(voff, |s| s.start)));
                }
                Some(axis)
            }
            (None, Some((n, off))) => {
                let Some(name) = label(n) else {
                    self.problem(
                        off,
                        format!("{scope}, key 'name': expected a non-empty string"),
                    );
                    return None;
                };
                let Some(table) = values.as_table_like() else {
                    self.problem(voff, format!("{scope}, key 'values': a named axis takes a table of value = [\"KEY=VALUE\", …]"));
                    return None;
                };
                let mut out = Vec::new();
                for (label, item) in table.iter() {
                    let off = table
                        .key(label)
                        .and_then(Key::span)
                        .map_or(voff, |s| s.start);
                    let sets = self.strings(item, off, &format!("{scope}, value '{label}'"));
                    out.push(AxisValue {
                        label: label.to_string(),
                        sets,
                        origin: Some(self.at(off)),
                    });
                }
                let labels: Vec<String> = out.iter().map(|v| v.label.clone()).collect();
                self.check_values(&scope, voff, &labels)?;
                Some(Axis {
                    label: name.to_string(),
                    key: None,
                    values: out,
                })
            }
            (Some((_, off)), Some(_)) => {
                self.problem(off, format!("{scope}: give either 'key' (one --set key) or 'name' (bundles of sets), not both"));
                None
            }
            (None, None) => {
                self.problem(
                    at,
                    format!("{scope}: missing 'key' (one --set key) or 'name' (bundles of sets)"),
                );
                None
            }
        }
    }

    fn check_values(&mut self, scope: &str, off: usize, labels: &[String]) -> Option<()> {
        if labels.is_empty() {
            self.problem(off, format!("{scope}, key 'values': no values"));
            return None;
        }
        let mut seen = std::collections::BTreeSet::new();
        if let Some(dup) = labels.iter().find(|l| !seen.insert(l.as_str())) {
            self.problem(off, format!("{scope}, key 'values': '{dup}' given twice"));
            return None;
        }
        Some(())
    }

    /// A list of `KEY=VALUE` strings.
    fn strings(&mut self, item: &Item, off: usize, what: &str) -> Vec<String> {
        let list = item.as_array().map(|a| {
            a.iter()
                .map(|v| v.as_str().map(str::to_string))
                .collect::<Option<Vec<_>>>()
        });
        match list {
            Some(Some(sets)) => {
                if let Some(bad) = sets.iter().find(|s| !s.contains('=')) {
                    self.problem(off, format!("{what}: '{bad}' is not KEY=VALUE"));
                }
                sets
            }
            _ => {
                self.problem(
                    off,
                    format!("{what}: expected a list of \"KEY=VALUE\" strings"),
                );
                Vec::new()
            }
        }
    }
}

/// `seeds = "1..=3"` or `seeds = [1, 2, 3]`.
fn seeds(item: &Item) -> Result<Vec<u64>, String> {
    if let Some(spec) = item.as_str() {
        return caravan_report::seeds::parse(spec);
    }
    let list = item
        .as_array()
        .ok_or("expected a spec like \"1..=3\" or a list like [1, 2, 3]")?;
    let seeds = list
        .iter()
        .map(|v| {
            v.as_integer()
                .and_then(|n| u64::try_from(n).ok())
                .ok_or("seeds are whole numbers ≥ 0")
        })
        .collect::<Result<Vec<u64>, _>>()?;
    caravan_report::seeds::check(&seeds)?;
    Ok(seeds)
}

/// The text of a TOML value without its decoration.
fn bare(v: &Value) -> String {
    let mut v = v.clone();
    v.decor_mut().clear();
    v.to_string()
}

/// The `--set` text of an axis value, keeping its TOML type: a string is written bare when
/// `--set` would read it back as that same string (`ideal`, `2ms`), quoted otherwise (`"3"`).
fn set_text(v: &Value) -> String {
    match v.as_str() {
        Some(s) if parse_value(s).as_str() == Some(s) => s.to_string(),
        _ => bare(v),
    }
}

/// A non-empty string, trimmed.
fn label(item: &Item) -> Option<&str> {
    item.as_str().map(str::trim).filter(|s| !s.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;

    const FIG9A: &str = r#"# the follower-deviation experiment
[sweep]
name = "fig9a"
launch = "pingpong.toml"
seeds = "1..=3"
set = ["group.duration=120s"]
jobs = 2

[[sweep.axis]]
key = "args.localisation"
values = ["estimated", "ideal"]

[[sweep.axis]]
name = "network"
[sweep.axis.values]
no-delay = []
wlan = ["args.wlan_latency=2ms"]
bad-wlan = ["args.wlan_latency=50ms", "args.wlan_loss=0.05"]
"#;

    fn parse_in(dir: &Path, text: &str) -> Result<SweepFile, Vec<String>> {
        std::fs::create_dir_all(dir).unwrap();
        std::fs::write(dir.join("pingpong.toml"), "").unwrap();
        parse(&dir.join("s.toml"), text)
    }

    fn tmp(tag: &str) -> PathBuf {
        std::env::temp_dir().join(format!("caravan-sweepfile-{tag}-{}", std::process::id()))
    }

    #[test]
    fn a_full_sweep_file() {
        let dir = tmp("full");
        let f = parse_in(&dir, FIG9A).unwrap();
        assert_eq!(f.name, "fig9a");
        assert_eq!(f.launch, dir.join("pingpong.toml"));
        assert_eq!(f.seeds, Some(vec![1, 2, 3]));
        assert_eq!(f.sets, ["group.duration=120s"]);
        assert_eq!(f.jobs, Some(2));
        assert_eq!(f.axes.len(), 2);
        assert_eq!(f.axes[0].values[1].sets, ["args.localisation=ideal"]);
        assert_eq!(f.axes[1].label, "network");
        assert_eq!(f.axes[1].values[2].label, "bad-wlan");
        assert_eq!(f.axes[1].values[2].sets.len(), 2);
        assert!(f.axes[1].values[0].sets.is_empty());
        assert!(is_sweep_file(FIG9A));
        assert!(!is_sweep_file("[group]\nname = \"x\"\n"));
        assert!(!is_sweep_file("[sweep"));
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn values_keep_their_toml_type() {
        let dir = tmp("typed");
        let text = "[sweep]\nlaunch = \"pingpong.toml\"\nseeds = [4, 5]\n[[sweep.axis]]\nkey = \"process.pong.params.gain\"\nvalues = [1, 2.5, \"3\", \"fast\"]\n";
        let f = parse_in(&dir, text).unwrap();
        assert_eq!(f.name, "s");
        assert_eq!(f.seeds, Some(vec![4, 5]));
        let sets: Vec<_> = f.axes[0]
            .values
            .iter()
            .map(|v| v.sets[0].as_str())
            .collect();
        assert_eq!(
            sets,
            [
                "process.pong.params.gain=1",
                "process.pong.params.gain=2.5",
                "process.pong.params.gain=\"3\"",
                "process.pong.params.gain=fast"
            ]
        );
        let labels: Vec<_> = f.axes[0].values.iter().map(|v| v.label.as_str()).collect();
        assert_eq!(labels, ["1", "2.5", "3", "fast"]);
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn problems_name_file_line_and_key() {
        let dir = tmp("bad");
        let text = "[sweep]\nlaunch = \"pingpong.toml\"\nseed = 3\njobs = 0\n[[sweep.axis]]\nkey = \"args.x\"\nvalues = []\n[[sweep.axis]]\nname = \"net\"\nvalues = [1]\n[other]\n";
        let errs = parse_in(&dir, text).unwrap_err();
        let s = dir.join("s.toml").display().to_string();
        assert_eq!(
            errs,
            [
                format!("{s}:3: [sweep] key 'seed': unknown key; did you mean 'seeds'?"),
                format!("{s}:4: [sweep] key 'jobs': expected a whole number ≥ 1"),
                format!("{s}:7: [[sweep.axis]] #1, key 'values': no values"),
                format!(
                    "{s}:10: [[sweep.axis]] #2, key 'values': a named axis takes a table of value = [\"KEY=VALUE\", …]"
                ),
                format!("{s}:11: key 'other': unknown key; expected one of: sweep"),
            ]
        );
        let errs = parse_in(&dir, "[sweep]\nname = \"x\"\n").unwrap_err();
        assert_eq!(
            errs,
            [format!("{s}:1: [sweep]: missing required key 'launch'")]
        );
        let errs = parse_in(&dir, "[sweep]\nlaunch = \"nope.toml\"\n").unwrap_err();
        assert!(errs[0].starts_with(&format!("{s}:2: ")), "{errs:?}");
        let errs = parse_in(
            &dir,
            "[sweep]\nlaunch = 'pingpong.toml'\nseeds = \"3..1\"\n",
        )
        .unwrap_err();
        assert!(errs[0].contains(":3: [sweep] key 'seeds'"), "{errs:?}");
        let _ = std::fs::remove_dir_all(dir);
    }
}
