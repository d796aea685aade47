//! `caravan sweep merge OUT [DIR…]`: joins the outputs of a sweep's shards (run on other
//! machines, or as a job array into one shared folder) into the one `summary.json` and
//! `summary.csv` that a local run of the whole sweep writes.
//!
//! The sweep is rebuilt from the shards' manifests, which must agree (same fingerprint, same
//! Caravan); each run is taken from the first DIR holding it finished. Missing runs are named,
//! with their shards, and nothing is written unless `--allow-missing` says to summarise what
//! is there.

use super::manifest::{self, Manifest};
use super::shard::Shard;
use super::{entry, grid, runner, summary};
use anyhow::{Context, Result};
use caravan_group::launch::EXIT_BAD_INPUT;
use clap::Args;
use std::collections::BTreeSet;
use std::path::{Component, Path, PathBuf};

#[derive(Args)]
pub struct MergeArgs {
    /// Where summary.json and summary.csv go
    pub out: PathBuf,
    /// The shards' output directories (default: OUT itself, as when the shards shared it)
    pub dirs: Vec<PathBuf>,
    /// Summarise the runs that are there even when some are missing (they are still listed)
    #[arg(long)]
    pub allow_missing: bool,
    /// Print only these metrics (`*` matches anything); the files hold all of them
    #[arg(long = "metric", value_name = "KEY")]
    pub metric: Vec<String>,
}

/// Merges; returns the exit code: 0 every run completed, 1 some did not (the summary is
/// written), 2 bad input (shards of different sweeps, missing runs; nothing written).
pub fn run(args: &MergeArgs) -> Result<u8> {
    let dirs = if args.dirs.is_empty() {
        vec![args.out.clone()]
    } else {
        args.dirs.clone()
    };
    if let Some(why) = caravan_group::bad_input::not_a_directory(&args.out) {
        return bad(vec![why]);
    }
    let manifests = match read_manifests(&dirs) {
        Ok(m) => m,
        Err(problems) => return bad(problems),
    };
    let sweep = &manifests[0].1.sweep;
    let axes = &sweep.axes;
    let cells = grid::expand(axes);

    let mut results: Vec<Vec<summary::RunEntry>> = vec![Vec::new(); cells.len()];
    let mut missing = Vec::new();
    let mut failed = Vec::new();
    let n = cells.len();
    for (s, &seed) in sweep.seeds.iter().enumerate() {
        for (c, cell) in cells.iter().enumerate() {
            let seed_dir =
                |dir: &Path| dir.join("runs").join(&cell.id).join(format!("seed-{seed}"));
            let found = dirs
                .iter()
                .find_map(|d| Some((d, runner::finished_run(&seed_dir(d))?)));
            let Some((dir, (run_dir, report))) = found else {
                missing.push((s * n + c, cell.id.as_str(), seed));
                continue;
            };
            let mut run = entry(dir, seed, &run_dir, None, Some(&report));
            run.dir = relative(&args.out, &dir.join(&run.dir));
            if run.outcome != "completed" {
                failed.push(format!(
                    "cell {} seed {seed}: {}; see {}",
                    cell.id,
                    run.outcome,
                    seed_dir(dir).join("launch.log").display()
                ));
            }
            results[c].push(run);
        }
    }
    if !missing.is_empty() {
        let listed = missing_runs(&missing, &manifests);
        if !args.allow_missing {
            listed.iter().for_each(|l| eprintln!("caravan: {l}"));
            eprintln!(
                "caravan: nothing written: run the missing shards (a resubmitted sweep runs only \
                 unfinished runs), or summarise what is there with --allow-missing"
            );
            return Ok(EXIT_BAD_INPUT);
        }
        listed
            .iter()
            .for_each(|l| eprintln!("caravan: warning: {l}"));
    }
    let header = summary::Header {
        name: &sweep.name,
        launch: &sweep.launch,
        seeds: &sweep.seeds,
        axes,
    };
    let doc = summary::summarise(&header, &cells, &results);
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    summary::write(&args.out, &doc)?;
    print!("{}", summary::table(&doc, &args.metric));
    failed.iter().for_each(|f| eprintln!("caravan: {f}"));
    let done: usize = results.iter().map(Vec::len).sum();
    eprintln!(
        "caravan: merged {done} runs of sweep '{}' from {} shard manifests in {} {}; {} \
         completed; summary in {} and summary.csv",
        sweep.name,
        manifests.len(),
        dirs.len(),
        if dirs.len() == 1 {
            "directory"
        } else {
            "directories"
        },
        done - failed.len(),
        args.out.join("summary.json").display()
    );
    Ok(if failed.is_empty() { 0 } else { 1 })
}

fn bad(problems: Vec<String>) -> Result<u8> {
    problems.iter().for_each(|p| eprintln!("caravan: {p}"));
    Ok(EXIT_BAD_INPUT)
}

/// Every DIR's manifests; they must all be of one sweep, run by one Caravan.
fn read_manifests(dirs: &[PathBuf]) -> Result<Vec<(PathBuf, Manifest)>, Vec<String>> {
    let mut all = Vec::new();
    let mut problems = Vec::new();
    for dir in dirs {
        match manifest::read_all(dir) {
            Ok(m) => all.extend(m),
            Err(e) => problems.push(e),
        }
    }
    if !problems.is_empty() {
        return Err(problems);
    }
    let (first_path, first) = &all[0];
    for (path, m) in &all[1..] {
        if m.fingerprint != first.fingerprint {
            let mut differs = differences(&first.sweep, &m.sweep);
            if differs.is_empty() {
                differs.push("their definitions differ".into());
            }
            problems.push(format!(
                "{} is a shard of another sweep than {} ({}): shards of different sweeps are \
                 not merged",
                path.display(),
                first_path.display(),
                differs.join(", ")
            ));
        } else if m.caravan != first.caravan {
            problems.push(format!(
                "{} was run by Caravan {}, {} by Caravan {}: shards of different versions are \
                 not merged",
                path.display(),
                m.caravan,
                first_path.display(),
                first.caravan
            ));
        }
    }
    if problems.is_empty() {
        Ok(all)
    } else {
        Err(problems)
    }
}

/// What differs between two sweeps' definitions, by field.
fn differences(a: &manifest::Definition, b: &manifest::Definition) -> Vec<String> {
    let mut out = Vec::new();
    let mut field = |name: &str, x: String, y: String| {
        if x != y {
            out.push(format!("{name} {x} against {y}"));
        }
    };
    field("name", a.name.clone(), b.name.clone());
    field(
        "launch file",
        a.launch.display().to_string(),
        b.launch.display().to_string(),
    );
    if a.launch == b.launch {
        field(
            "launch file's contents (hash)",
            a.launch_hash.clone(),
            b.launch_hash.clone(),
        );
    }
    field("seeds", format!("{:?}", a.seeds), format!("{:?}", b.seeds));
    field("sets", format!("{:?}", a.sets), format!("{:?}", b.sets));
    field(
        "duration",
        format!("{:?}", a.duration),
        format!("{:?}", b.duration),
    );
    let axes = |d: &manifest::Definition| {
        let each: Vec<String> = (d.axes.iter())
            .map(|a| {
                let values: Vec<&str> = a.values.iter().map(|v| v.label.as_str()).collect();
                format!("{}={}", a.label, values.join(","))
            })
            .collect();
        format!("[{}]", each.join("; "))
    };
    field("axes", axes(a), axes(b));
    out
}

/// The missing runs, grouped by the shard each belongs to under every split the manifests
/// show, and the shards that never wrote a manifest.
fn missing_runs(missing: &[(usize, &str, u64)], manifests: &[(PathBuf, Manifest)]) -> Vec<String> {
    let have: BTreeSet<Shard> = manifests.iter().map(|(_, m)| m.shard()).collect();
    let splits: BTreeSet<usize> = have.iter().map(|s| s.n).collect();
    let mut lines = Vec::new();
    let names = |runs: &[&(usize, &str, u64)]| {
        let mut text: Vec<String> = runs
            .iter()
            .take(5)
            .map(|(_, cell, seed)| format!("cell {cell} seed {seed}"))
            .collect();
        if runs.len() > 5 {
            text.push(format!("and {} more", runs.len() - 5));
        }
        text.join("; ")
    };
    for &n in &splits {
        for k in 1..=n {
            let shard = Shard { k, n };
            let runs: Vec<_> = missing
                .iter()
                .filter(|(i, _, _)| Shard::of(*i, n) == shard)
                .collect();
            if runs.is_empty() {
                continue;
            }
            let state = if have.contains(&shard) {
                "started but did not finish"
            } else {
                "has no manifest in any directory (never started?)"
            };
            lines.push(format!(
                "shard {shard} {state}: {} runs missing: {}",
                runs.len(),
                names(&runs)
            ));
        }
    }
    lines
}

/// `path` relative to `base` (both made absolute), as the summary's `dir` is relative to the
/// folder it is in.
fn relative(base: &Path, path: &Path) -> String {
    let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let (base, path) = (abs(base), abs(path));
    let b: Vec<Component> = base.components().collect();
    let p: Vec<Component> = path.components().collect();
    let common = b.iter().zip(&p).take_while(|(x, y)| x == y).count();
    let mut rel = PathBuf::new();
    for _ in common..b.len() {
        rel.push("..");
    }
    for c in &p[common..] {
        rel.push(c);
    }
    rel.display().to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths() {
        assert_eq!(
            relative(Path::new("/a/b"), Path::new("/a/b/runs/x")),
            "runs/x"
        );
        assert_eq!(
            relative(Path::new("/a/merged"), Path::new("/a/s1/runs/x")),
            "../s1/runs/x"
        );
    }
}
