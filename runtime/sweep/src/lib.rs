//! `caravan sweep`: runs a launch file over a grid of overrides × seeds, several groups at
//! once, each as its own `caravan launch` child, then summarises the reports per cell.
//! Documented in docs/sweep.md.

mod file;
mod grid;
mod runner;
mod summary;

use anyhow::{Context, Result};
use caravan_group::launch::{EXIT_BAD_INPUT, LaunchArgs};
use caravan_launch::LaunchError;
use clap::Args;
use grid::{Axis, Cell};
use indicatif::{ProgressBar, ProgressStyle};
use runner::{Finished, Task};
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use summary::RunEntry;

#[derive(Args)]
pub struct SweepArgs {
    /// A launch file, or a sweep file (TOML with a top-level [sweep] table)
    pub target: PathBuf,
    /// An axis: a `--set` key and its values, e.g. `process.pong.params.gain=1,3`; several
    /// make the Cartesian product
    #[arg(long = "grid", value_name = "KEY=V1,V2,…")]
    pub grid: Vec<String>,
    /// An override applied to every run, as in `caravan launch --set`
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Seeds: `1,2,3`, `1..=3` or `1..4` (default 1, or the sweep file's)
    #[arg(long, value_name = "SPEC")]
    pub seeds: Option<String>,
    /// How many groups run at once (default: the number of cores, or the sweep file's)
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Output directory (default `sweeps/<name>`)
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Run each group for this long, e.g. `30s`
    #[arg(long)]
    pub duration: Option<String>,
    /// Print only these metrics (`*` matches anything); the files hold all of them
    #[arg(long = "metric", value_name = "KEY")]
    pub metric: Vec<String>,
    /// No progress bar
    #[arg(long)]
    pub quiet: bool,
}

/// Exit code after Ctrl-C (128 + SIGINT, as shells report it).
pub const EXIT_INTERRUPTED: u8 = 130;

/// Everything the sweep will do, checked before anything runs.
struct Plan {
    name: String,
    launch: PathBuf,
    seeds: Vec<u64>,
    /// Overrides of every run: the sweep file's, then the command line's.
    sets: Vec<String>,
    axes: Vec<Axis>,
    cells: Vec<Cell>,
    jobs: usize,
    out: PathBuf,
    duration: Option<String>,
}

impl Plan {
    /// The `--set`s of one run of `cell`. The cell's come after the common ones and the
    /// sweep's group name last, so every concurrent group has its own name.
    fn sets(&self, cell: &Cell, group: &str) -> Vec<String> {
        let mut sets = self.sets.clone();
        sets.extend(cell.sets.iter().cloned());
        sets.push(format!("group.name={group}"));
        sets
    }
}

/// Runs the sweep; returns the exit code (0 all completed, 1 a run failed, 2 bad input,
/// 130 interrupted).
pub fn run(args: &SweepArgs) -> Result<u8> {
    let plan = match plan(args) {
        Ok(p) => p,
        Err(problems) => {
            for p in problems {
                eprintln!("caravan: {p}");
            }
            return Ok(EXIT_BAD_INPUT);
        }
    };
    let prefix = group_prefix(&plan.name);
    let runs_root = plan.out.join("runs");
    let mut results: Vec<Vec<RunEntry>> = vec![Vec::new(); plan.cells.len()];
    let mut tasks = Vec::new();
    // Seed-major, so that an interrupted sweep has every cell's first seeds.
    for &seed in &plan.seeds {
        for (c, cell) in plan.cells.iter().enumerate() {
            let dir = runs_root.join(&cell.id).join(format!("seed-{seed}"));
            if let Some((run_dir, report)) = runner::finished_run(&dir) {
                results[c].push(entry(&plan.out, seed, &run_dir, None, Some(&report)));
                continue;
            }
            // Left by a killed sweep: start that run afresh.
            if dir.exists() {
                std::fs::remove_dir_all(&dir)
                    .with_context(|| format!("cannot remove {}", dir.display()))?;
            }
            let group = format!("{prefix}-{}-{}", std::process::id(), tasks.len());
            tasks.push(Task {
                cell: c,
                seed,
                args: launch_args(&plan, cell, seed, &dir, &group),
                dir,
                group,
            });
        }
    }
    let total = plan.cells.len() * plan.seeds.len();
    let skipped = total - tasks.len();
    eprintln!(
        "caravan: sweep '{}': {} cells × {} seeds = {total} runs of {} into {}",
        plan.name,
        plan.cells.len(),
        plan.seeds.len(),
        plan.launch.display(),
        plan.out.display()
    );
    if skipped > 0 {
        eprintln!(
            "caravan: skipped {skipped} of {total} runs: already finished (their reports are reused)"
        );
    }
    if !tasks.is_empty() {
        let jobs = plan.jobs.min(tasks.len());
        eprintln!("caravan: running {} runs, {jobs} at a time", tasks.len());
    }

    let bar = if args.quiet || tasks.is_empty() {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(tasks.len() as u64).with_style(
            ProgressStyle::with_template("{bar:30} {pos}/{len} runs, {msg}, ETA {eta}")
                .expect("valid template"),
        )
    };
    bar.set_message("0 failed");
    let mut failed = Vec::new();
    let on_done = |f: Finished| {
        bar.inc(1);
        if f.interrupted {
            return;
        }
        let id = &plan.cells[f.cell].id;
        let seed_dir = runs_root.join(id).join(format!("seed-{}", f.seed));
        let outcome = outcome_of(f.report.as_ref());
        if outcome != "completed" {
            let log = seed_dir.join("launch.log");
            failed.push(match &f.error {
                Some(e) => format!("cell {id} seed {}: {e}", f.seed),
                None => format!(
                    "cell {id} seed {}: {outcome}; see {}",
                    f.seed,
                    log.display()
                ),
            });
            bar.set_message(format!("{} failed", failed.len()));
        }
        let dir = f.run_dir.as_deref().unwrap_or(&seed_dir);
        let run = entry(&plan.out, f.seed, dir, Some(f.exit_code), f.report.as_ref());
        results[f.cell].push(run);
    };
    let jobs = plan.jobs.min(tasks.len()).max(1);
    let interrupted = runner::run_all(tasks, jobs, on_done)?;
    bar.finish_and_clear();

    for runs in &mut results {
        runs.sort_by_key(|r| plan.seeds.iter().position(|&s| s == r.seed));
    }
    let header = summary::Header {
        name: &plan.name,
        launch: &plan.launch,
        seeds: &plan.seeds,
        axes: &plan.axes,
    };
    let doc = summary::summarise(&header, &plan.cells, &results);
    std::fs::create_dir_all(&plan.out)
        .with_context(|| format!("cannot create {}", plan.out.display()))?;
    summary::write(&plan.out, &doc)?;
    print!("{}", summary::table(&doc, &args.metric));
    for f in &failed {
        eprintln!("caravan: {f}");
    }
    let done: usize = results.iter().map(Vec::len).sum();
    let all_completed = results.iter().flatten().all(|r| r.outcome == "completed");
    if interrupted {
        eprintln!(
            "caravan: interrupted; {done} of {total} runs finished, summarised in {}",
            plan.out.join("summary.json").display()
        );
        return Ok(EXIT_INTERRUPTED);
    }
    let not_completed = results
        .iter()
        .flatten()
        .filter(|r| r.outcome != "completed");
    eprintln!(
        "caravan: {} of {done} runs completed; summary in {} and summary.csv",
        done - not_completed.count(),
        plan.out.join("summary.json").display()
    );
    Ok(if all_completed { 0 } else { 1 })
}

fn outcome_of(report: Option<&serde_json::Value>) -> &str {
    report
        .and_then(|r| r["run"]["outcome"].as_str())
        .unwrap_or("error")
}

/// A run for the summary. `exit_code` is `None` for a reused run: then it is the code the
/// launcher gives that outcome, so a resumed sweep writes the same summary.
fn entry(
    out: &Path,
    seed: u64,
    dir: &Path,
    exit_code: Option<Option<i32>>,
    report: Option<&serde_json::Value>,
) -> RunEntry {
    let outcome = outcome_of(report).to_string();
    let exit_code = exit_code.unwrap_or(match outcome.as_str() {
        "completed" => Some(0),
        _ => Some(1),
    });
    let dir = dir.strip_prefix(out).unwrap_or(dir).display().to_string();
    RunEntry {
        seed,
        dir,
        exit_code,
        outcome,
        leaves: summary::flatten(report),
    }
}

fn launch_args(plan: &Plan, cell: &Cell, seed: u64, dir: &Path, group: &str) -> Vec<OsString> {
    let mut a: Vec<OsString> = vec![
        "launch".into(),
        plan.launch.clone().into(),
        "--quiet".into(),
        "--runs-dir".into(),
        dir.into(),
        "--seed".into(),
        seed.to_string().into(),
    ];
    if let Some(d) = &plan.duration {
        a.extend(["--duration".into(), d.into()]);
    }
    for s in plan.sets(cell, group) {
        a.extend(["--set".into(), s.into()]);
    }
    a
}

/// The start of the sweep's group names: `<name>-<pid>-<n>` must fit in 40 characters of
/// [A-Za-z0-9-] and differ from every other sweep's, hence the pid.
fn group_prefix(name: &str) -> String {
    let clean: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .take(20)
        .collect();
    let clean = clean.trim_matches('-');
    if clean.is_empty() {
        "sweep".into()
    } else {
        clean.into()
    }
}

/// Reads the target and the command line into a plan and validates every cell.
fn plan(args: &SweepArgs) -> Result<Plan, Vec<String>> {
    let target = &args.target;
    let text = std::fs::read_to_string(target)
        .map_err(|e| vec![format!("cannot read {}: {e}", target.display())])?;
    let mut sweep = if file::is_sweep_file(&text) {
        file::parse(target, &text)?
    } else {
        let stem = target
            .file_stem()
            .map_or("sweep".into(), |s| s.to_string_lossy().into_owned());
        file::SweepFile {
            name: stem,
            launch: target.clone(),
            seeds: None,
            sets: Vec::new(),
            jobs: None,
            axes: Vec::new(),
        }
    };
    let mut problems = Vec::new();
    for g in &args.grid {
        match grid::parse_grid(g) {
            Ok(axis) => grid::merge_axis(&mut sweep.axes, axis),
            Err(e) => problems.push(e),
        }
    }
    let seeds = match &args.seeds {
        Some(spec) => grid::parse_seeds(spec).unwrap_or_else(|e| {
            problems.push(format!("--seeds {spec}: {e}"));
            Vec::new()
        }),
        None => sweep.seeds.clone().unwrap_or_else(|| vec![1]),
    };
    // The sweep names every group and sets every seed itself; an axis or a set over those
    // keys would be replaced without a word.
    let owned = |set: &str| {
        let key = set.split_once('=').map_or(set, |(k, _)| k).trim();
        matches!(key, "group.name" | "group.seed")
    };
    for axis in &sweep.axes {
        for set in axis.values.iter().flat_map(|v| &v.sets) {
            if owned(set) {
                problems.push(format!(
                    "axis '{}': '{set}': the sweep sets group.name and group.seed itself (use seeds for seeds)",
                    axis.label
                ));
            }
        }
    }
    for set in sweep.sets.iter().chain(&args.set) {
        if owned(set) {
            problems.push(format!(
                "'{set}': the sweep sets group.name and group.seed itself (use seeds for seeds)"
            ));
        }
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let jobs = args.jobs.or(sweep.jobs).unwrap_or(cores);
    if jobs == 0 {
        problems.push("--jobs must be at least 1".into());
    }
    if !problems.is_empty() {
        return Err(problems);
    }
    let mut sets = sweep.sets;
    sets.extend(args.set.iter().cloned());
    let out = args.out.clone().unwrap_or_else(|| {
        let dir: String = sweep
            .name
            .chars()
            .map(|c| if c == '/' || c == '\\' { '_' } else { c })
            .collect();
        Path::new("sweeps").join(dir)
    });
    let plan = Plan {
        name: sweep.name,
        launch: sweep.launch,
        seeds,
        sets,
        cells: grid::expand(&sweep.axes),
        axes: sweep.axes,
        jobs,
        out,
        duration: args.duration.clone(),
    };
    let problems = validate(&plan);
    if problems.is_empty() {
        Ok(plan)
    } else {
        Err(problems)
    }
}

/// Loads the launch file with every cell's overrides, as `caravan launch` would, without
/// starting anything. A problem shared by several cells is reported once, naming them.
fn validate(plan: &Plan) -> Vec<String> {
    // The output must be a directory (made, or resumed); a file there is bad input.
    if plan.out.exists() && !plan.out.is_dir() {
        return vec![format!(
            "--out {}: exists and is not a directory",
            plan.out.display()
        )];
    }
    let mut problems: Vec<(String, Vec<&str>)> = Vec::new();
    for cell in &plan.cells {
        let args = LaunchArgs {
            file: plan.launch.clone(),
            set: plan.sets(cell, &format!("{}-check", group_prefix(&plan.name))),
            duration: plan.duration.clone(),
            clock: None,
            seed: plan.seeds.first().copied(),
            runs_dir: PathBuf::new(),
            quiet: true,
            foxglove: None,
            play: None,
            play_topics: Vec::new(),
            only: Vec::new(),
            host: None,
        };
        match caravan_group::launch::load(&args) {
            Ok(_) => {}
            Err(e @ LaunchError::Read { .. }) => return vec![e.to_string()],
            Err(LaunchError::Invalid(list)) => {
                for p in list {
                    let text = p.to_string();
                    match problems.iter_mut().find(|(t, _)| *t == text) {
                        Some((_, cells)) => cells.push(&cell.id),
                        None => problems.push((text, vec![&cell.id])),
                    }
                }
            }
        }
    }
    let n = plan.cells.len();
    problems
        .into_iter()
        .map(|(text, cells)| match cells.len() {
            _ if plan.axes.is_empty() => text,
            k if k == n => format!("{text} (every cell)"),
            1 => format!("cell {}: {text}", cells[0]),
            _ => format!("cells {}: {text}", cells.join("; ")),
        })
        .collect()
}
