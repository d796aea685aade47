//! The sweep summary: each run's `report.json` flattened into dotted keys, then statistics per
//! cell and metric, written as `summary.json` and `summary.csv` and printed as a short table.

use super::grid::{Axis, Cell};
use anyhow::{Context, Result};
use caravan_launch::value_json;
use caravan_report::stats::describe;
use caravan_report::wilson::wilson95;
use serde_json::{Map, Value, json};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// One leaf of a flattened report.
#[derive(Debug, Clone, PartialEq)]
pub enum Leaf {
    Number(f64),
    Flag(bool),
}

/// Top-level report sections that identify a run rather than measure it.
const SKIPPED_SECTIONS: &[&str] = &["version", "group"];

/// Flattens a report into dotted keys: objects by key; arrays by position, or by the elements'
/// `name` when every element has a distinct one (`nodes.pong.steps`, `topics.demo/ping.messages`,
/// but `convoy.followers.0.cross_track_to_leader_m.mean`). Numbers and booleans are kept;
/// strings and nulls are skipped, as are `version` and `group` (identity, not measurement).
/// Adds the flag `run.completed` (outcome is "completed"), also for a run without a report.
pub fn flatten(report: Option<&Value>) -> BTreeMap<String, Leaf> {
    let mut out = BTreeMap::new();
    if let Some(Value::Object(top)) = report {
        for (key, value) in top {
            if !SKIPPED_SECTIONS.contains(&key.as_str()) {
                walk(value, key.clone(), &mut out);
            }
        }
    }
    let completed = report.is_some_and(|r| r["run"]["outcome"] == "completed");
    out.insert("run.completed".into(), Leaf::Flag(completed));
    out
}

fn walk(value: &Value, key: String, out: &mut BTreeMap<String, Leaf>) {
    match value {
        Value::Number(n) => {
            if let Some(x) = n.as_f64().filter(|x| x.is_finite()) {
                out.insert(key, Leaf::Number(x));
            }
        }
        Value::Bool(b) => {
            out.insert(key, Leaf::Flag(*b));
        }
        Value::Object(map) => {
            for (k, v) in map {
                walk(v, format!("{key}.{k}"), out);
            }
        }
        Value::Array(items) => {
            let names: Option<Vec<&str>> = items.iter().map(|i| i["name"].as_str()).collect();
            let distinct = names.as_ref().is_some_and(|n| {
                let mut sorted = n.clone();
                sorted.sort_unstable();
                sorted.dedup();
                sorted.len() == n.len()
            });
            for (i, item) in items.iter().enumerate() {
                let part = match &names {
                    Some(n) if distinct => n[i].to_string(),
                    _ => i.to_string(),
                };
                walk(item, format!("{key}.{part}"), out);
            }
        }
        Value::String(_) | Value::Null => {}
    }
}

/// One run as the summary sees it.
#[derive(Debug, Clone)]
pub struct RunEntry {
    pub seed: u64,
    /// The run directory (or, without one, the seed's directory), relative to the sweep's.
    pub dir: String,
    pub exit_code: Option<i32>,
    /// The report's `run.outcome`, or "error" when the run left no report.
    pub outcome: String,
    pub leaves: BTreeMap<String, Leaf>,
}

/// What the summary says about the sweep as a whole.
pub struct Header<'a> {
    pub name: &'a str,
    pub launch: &'a Path,
    pub seeds: &'a [u64],
    pub axes: &'a [Axis],
}

/// The summary document (`summary.json`); `runs[c]` are the finished runs of `cells[c]`.
pub fn summarise(header: &Header, cells: &[Cell], runs: &[Vec<RunEntry>]) -> Value {
    let axes: Vec<Value> = header
        .axes
        .iter()
        .map(|a| {
            let values: Vec<&str> = a.values.iter().map(|v| v.label.as_str()).collect();
            match &a.key {
                Some(key) => {
                    let typed: Vec<Value> = values.iter().map(|v| value_json(v)).collect();
                    json!({"key": key, "values": typed})
                }
                None => {
                    let sets: Map<String, Value> = a
                        .values
                        .iter()
                        .map(|v| (v.label.clone(), json!(v.sets)))
                        .collect();
                    json!({"name": a.label, "values": values, "sets": sets})
                }
            }
        })
        .collect();
    let plain: Vec<&str> = header
        .axes
        .iter()
        .filter(|a| a.key.is_some())
        .map(|a| a.label.as_str())
        .collect();
    let cells: Vec<Value> = cells
        .iter()
        .zip(runs)
        .map(|(cell, runs)| cell_summary(cell, runs, &plain))
        .collect();
    json!({
        "name": header.name,
        "launch": header.launch.display().to_string(),
        "seeds": header.seeds,
        "axes": axes,
        "cells": cells,
    })
}

/// `plain` names the axes over a key, whose values are typed as `--set` reads them (a named
/// axis' value is its name).
fn cell_summary(cell: &Cell, runs: &[RunEntry], plain: &[&str]) -> Value {
    let mut numbers: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
    let mut flags: BTreeMap<&str, (usize, usize)> = BTreeMap::new();
    for run in runs {
        for (key, leaf) in &run.leaves {
            match leaf {
                Leaf::Number(x) => numbers.entry(key).or_default().push(*x),
                Leaf::Flag(b) => {
                    let f = flags.entry(key).or_default();
                    f.0 += usize::from(*b);
                    f.1 += 1;
                }
            }
        }
    }
    let metrics: Map<String, Value> = numbers
        .into_iter()
        .map(|(key, xs)| {
            let d = describe(&xs);
            let v = json!({
                "n": d.n, "mean": d.mean, "sd": d.sd, "min": d.min, "max": d.max,
                "ci95": d.ci95.map(|(lo, hi)| [lo, hi]),
            });
            (key.to_string(), v)
        })
        .collect();
    let flags: Map<String, Value> = flags
        .into_iter()
        .map(|(key, (s, n))| {
            let (lo, hi) = wilson95(s, n);
            let v =
                json!({"successes": s, "n": n, "rate": s as f64 / n as f64, "wilson95": [lo, hi]});
            (key.to_string(), v)
        })
        .collect();
    let values: Map<String, Value> = cell
        .values
        .iter()
        .map(|(a, v)| {
            let typed = if plain.contains(&a.as_str()) {
                value_json(v)
            } else {
                json!(v)
            };
            (a.clone(), typed)
        })
        .collect();
    let sets: Map<String, Value> = cell
        .sets
        .iter()
        .filter_map(|s| s.split_once('='))
        .map(|(k, v)| (k.trim().to_string(), value_json(v)))
        .collect();
    let runs: Vec<Value> = runs
        .iter()
        .map(|r| json!({"seed": r.seed, "dir": r.dir, "exit_code": r.exit_code, "outcome": r.outcome}))
        .collect();
    json!({
        "id": cell.id, "values": values, "sets": sets, "runs": runs,
        "metrics": metrics, "flags": flags,
    })
}

/// Writes `summary.json` and `summary.csv` into `dir`.
pub fn write(dir: &Path, summary: &Value) -> Result<()> {
    let json_path = dir.join("summary.json");
    std::fs::write(&json_path, serde_json::to_string_pretty(summary)? + "\n")
        .with_context(|| format!("cannot write {}", json_path.display()))?;
    let csv_path = dir.join("summary.csv");
    std::fs::write(&csv_path, csv(summary))
        .with_context(|| format!("cannot write {}", csv_path.display()))
}

/// Long format: one row per (cell, metric). Axis columns first, then `cell,metric,kind`, then
/// the numbers. For `kind = flag`, `mean` is the success rate and `ci_lo`/`ci_hi` the Wilson
/// interval; `sd`, `min`, `max` are empty.
pub fn csv(summary: &Value) -> String {
    let axes: Vec<&str> = summary["axes"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|a| a["key"].as_str().or(a["name"].as_str()))
        .collect();
    let mut header: Vec<&str> = axes.clone();
    header.extend([
        "cell", "metric", "kind", "n", "mean", "sd", "min", "max", "ci_lo", "ci_hi",
    ]);
    let mut out = row(header.iter().map(|s| s.to_string()));
    let num = |v: &Value| v.as_f64().map_or(String::new(), |x| x.to_string());
    for cell in summary["cells"].as_array().into_iter().flatten() {
        let lead: Vec<String> = axes
            .iter()
            .map(|a| match &cell["values"][*a] {
                Value::String(s) => s.clone(),
                Value::Null => String::new(),
                v => v.to_string(),
            })
            .chain([cell["id"].as_str().unwrap_or("").to_string()])
            .collect();
        for (key, m) in cell["metrics"].as_object().into_iter().flatten() {
            let fields = [
                key.clone(),
                "number".into(),
                num(&m["n"]),
                num(&m["mean"]),
                num(&m["sd"]),
                num(&m["min"]),
                num(&m["max"]),
                num(&m["ci95"][0]),
                num(&m["ci95"][1]),
            ];
            out += &row(lead.iter().cloned().chain(fields));
        }
        for (key, f) in cell["flags"].as_object().into_iter().flatten() {
            let fields = [
                key.clone(),
                "flag".into(),
                num(&f["n"]),
                num(&f["rate"]),
                String::new(),
                String::new(),
                String::new(),
                num(&f["wilson95"][0]),
                num(&f["wilson95"][1]),
            ];
            out += &row(lead.iter().cloned().chain(fields));
        }
    }
    out
}

fn row(fields: impl Iterator<Item = String>) -> String {
    let quoted: Vec<String> = fields
        .map(|f| {
            if f.contains([',', '"', '\n']) {
                format!("\"{}\"", f.replace('"', "\"\""))
            } else {
                f
            }
        })
        .collect();
    quoted.join(",") + "\n"
}

/// Metrics printed when no `--metric` is given (those a report has).
pub const DEFAULT_METRICS: &[&str] = &[
    "run.completed",
    "run.real_time_factor",
    "convoy.goals_reached",
    "convoy.min_gap_m",
    "convoy.collisions",
    "convoy.order_kept",
    "slam.pose_error_m.mean",
];

/// `*` matches any run of characters, dots included.
pub fn glob(pattern: &str, text: &str) -> bool {
    match pattern.split_once('*') {
        None => pattern == text,
        Some((head, rest)) => {
            let Some(tail) = text.strip_prefix(head) else {
                return false;
            };
            (0..=tail.len())
                .filter(|&i| tail.is_char_boundary(i))
                .any(|i| glob(rest, &tail[i..]))
        }
    }
}

/// The table printed after a sweep: one line per cell and selected metric.
pub fn table(summary: &Value, patterns: &[String]) -> String {
    let wanted = |key: &str| {
        if patterns.is_empty() {
            DEFAULT_METRICS.contains(&key)
        } else {
            patterns.iter().any(|p| glob(p, key))
        }
    };
    let fmt = |v: &Value| v.as_f64().map_or("-".to_string(), short);
    let mut rows = vec![[
        "cell".to_string(),
        "metric".into(),
        "n".into(),
        "mean / rate".into(),
        "sd".into(),
        "95 % interval".into(),
    ]];
    for cell in summary["cells"].as_array().into_iter().flatten() {
        let id = cell["id"].as_str().unwrap_or("").to_string();
        let mut lines: Vec<(String, [String; 6])> = Vec::new();
        for (key, m) in cell["metrics"].as_object().into_iter().flatten() {
            if wanted(key) {
                let ci = match m["ci95"].as_array() {
                    Some(ci) => format!("[{}, {}]", fmt(&ci[0]), fmt(&ci[1])),
                    None => "-".into(),
                };
                let r = [
                    id.clone(),
                    key.clone(),
                    fmt(&m["n"]),
                    fmt(&m["mean"]),
                    fmt(&m["sd"]),
                    ci,
                ];
                lines.push((key.clone(), r));
            }
        }
        for (key, f) in cell["flags"].as_object().into_iter().flatten() {
            if wanted(key) {
                let w = &f["wilson95"];
                let rate = format!("{}/{}", f["successes"], f["n"]);
                let ci = format!("[{}, {}]", fmt(&w[0]), fmt(&w[1]));
                let r = [id.clone(), key.clone(), fmt(&f["n"]), rate, "-".into(), ci];
                lines.push((key.clone(), r));
            }
        }
        lines.sort_by(|a, b| a.0.cmp(&b.0));
        rows.extend(lines.into_iter().map(|(_, r)| r));
    }
    if rows.len() == 1 {
        return "no metric matches\n".into();
    }
    let widths: Vec<usize> = (0..6)
        .map(|c| rows.iter().map(|r| r[c].chars().count()).max().unwrap_or(0))
        .collect();
    let mut out = String::new();
    for r in &rows {
        let mut line = String::new();
        for (c, field) in r.iter().enumerate() {
            let _ = write!(line, "{field:<w$}  ", w = widths[c]);
        }
        out += line.trim_end();
        out.push('\n');
    }
    out
}

/// Four significant digits, without a trailing zero run.
fn short(x: f64) -> String {
    if x == x.trunc() && x.abs() < 1e9 {
        return format!("{x:.0}");
    }
    if x.abs() < 1e-3 {
        return format!("{x:.3e}");
    }
    let digits = (3 - x.abs().log10().floor() as i32).clamp(0, 9) as usize;
    format!("{x:.digits$}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::expand;

    fn report(outcome: &str, steps: u64, kept: bool) -> Value {
        json!({
            "version": 1,
            "group": {"name": "g", "seed": 3},
            "run": {"outcome": outcome, "failure": null, "real_time_factor": 2.5},
            "nodes": [{"name": "ping", "steps": steps, "period_ms": null}, {"name": "pong", "steps": 5}],
            "convoy": {"order_kept": kept, "goal_times_s": [1.5, 2.5],
                       "followers": [{"robot": 1, "cross_track_to_leader_m": {"mean": 0.25}}]},
        })
    }

    #[test]
    fn flattening_uses_names_indices_and_skips_text() {
        let flat = flatten(Some(&report("completed", 31, true)));
        let keys: Vec<&str> = flat.keys().map(String::as_str).collect();
        assert_eq!(
            keys,
            [
                "convoy.followers.0.cross_track_to_leader_m.mean",
                "convoy.followers.0.robot",
                "convoy.goal_times_s.0",
                "convoy.goal_times_s.1",
                "convoy.order_kept",
                "nodes.ping.steps",
                "nodes.pong.steps",
                "run.completed",
                "run.real_time_factor",
            ]
        );
        assert_eq!(flat["nodes.ping.steps"], Leaf::Number(31.0));
        assert_eq!(flat["run.completed"], Leaf::Flag(true));
        assert_eq!(flat["convoy.order_kept"], Leaf::Flag(true));
        // Without distinct names, positions.
        let dup = json!({"xs": [{"name": "a", "v": 1}, {"name": "a", "v": 2}]});
        assert!(flatten(Some(&dup)).contains_key("xs.1.v"));
        // A run without a report is still counted as not completed.
        let none = flatten(None);
        assert_eq!(none.len(), 1);
        assert_eq!(none["run.completed"], Leaf::Flag(false));
    }

    #[test]
    fn cells_get_statistics_and_flags() {
        let cells = expand(&[]);
        let runs: Vec<RunEntry> = [(1, 30, true), (2, 32, false)]
            .iter()
            .map(|&(seed, steps, kept)| RunEntry {
                seed,
                dir: format!("runs/all/seed-{seed}/g"),
                exit_code: Some(0),
                outcome: "completed".into(),
                leaves: flatten(Some(&report("completed", steps, kept))),
            })
            .collect();
        let header = Header {
            name: "t",
            launch: Path::new("launch/pingpong.toml"),
            seeds: &[1, 2],
            axes: &[],
        };
        let s = summarise(&header, &cells, &[runs]);
        let cell = &s["cells"][0];
        assert_eq!(cell["id"], "all");
        let steps = &cell["metrics"]["nodes.ping.steps"];
        assert_eq!(steps["n"], 2);
        assert_eq!(steps["mean"], 31.0);
        assert!((steps["sd"].as_f64().unwrap() - 2f64.sqrt()).abs() < 1e-12);
        let pong = &cell["metrics"]["nodes.pong.steps"];
        assert_eq!(pong["sd"], 0.0);
        assert_eq!(cell["flags"]["run.completed"]["rate"], 1.0);
        assert_eq!(cell["flags"]["convoy.order_kept"]["successes"], 1);
        assert_eq!(cell["runs"][1]["seed"], 2);
        let csv = csv(&s);
        assert!(csv.starts_with("cell,metric,kind,n,mean,sd,min,max,ci_lo,ci_hi\n"));
        assert!(csv.contains("\nall,nodes.ping.steps,number,2,31,"), "{csv}");
        assert!(csv.contains("\nall,run.completed,flag,2,1,,,,"), "{csv}");
        let t = table(&s, &[]);
        assert!(t.contains("run.completed") && t.contains("2/2"), "{t}");
        let t = table(&s, &["nodes.*.steps".into()]);
        assert!(
            t.contains("nodes.pong.steps") && !t.contains("run.completed"),
            "{t}"
        );
        assert_eq!(table(&s, &["nope".into()]), "no metric matches\n");
    }

    #[test]
    fn globs() {
        assert!(glob("nodes.*.steps", "nodes.pong.steps"));
        assert!(glob("*", "x"));
        assert!(glob("convoy.*", "convoy.followers.0.x"));
        assert!(!glob("nodes.*.steps", "nodes.pong.rate_hz"));
        assert!(glob("run.completed", "run.completed"));
        assert!(!glob("run", "run.completed"));
    }
}
