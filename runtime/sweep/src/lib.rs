//! `caravan sweep`: runs a launch file over a grid of overrides × seeds, several groups at
//! once, each as its own `caravan launch` child, then summarises the reports per cell.
//! Documented in docs/sweep.md.

mod file;
mod grid;
mod manifest;
mod merge;
mod plan;
mod runner;
mod shard;
mod slurm;
mod summary;

use anyhow::{Context, Result};
use caravan_group::launch::EXIT_BAD_INPUT;
use clap::{Args, Subcommand};
use grid::Cell;
use indicatif::{ProgressBar, ProgressStyle};
use plan::{Plan, group_prefix, plan};
use runner::{Finished, Task};
use std::ffi::OsString;
use std::path::{Path, PathBuf};
use summary::RunEntry;

#[derive(Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct SweepArgs {
    #[command(subcommand)]
    pub command: Option<SweepCommand>,
    /// A launch file, or a sweep file (TOML with a top-level [sweep] table)
    #[arg(required = true)]
    pub target: Option<PathBuf>,
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
    /// Run only shard K of N of the runs (`2/3`), or take it from a job array's environment:
    /// `env` (Slurm) or `env/N` (Slurm, Kubernetes' Indexed Jobs)
    #[arg(long, value_name = "K/N|env|env/N")]
    pub shard: Option<String>,
    /// Submit the sweep to Slurm as a job array of shards; what follows are sbatch options
    /// (`--slurm --time=1:00:00 --cpus-per-task=2`), so it comes last
    #[arg(long, num_args = 0.., allow_hyphen_values = true, value_name = "SBATCH-OPTION")]
    pub slurm: Option<Vec<String>>,
    /// With --slurm: how many array tasks (shards); default one per unfinished run, at most 1000
    #[arg(long, value_name = "N")]
    pub shards: Option<usize>,
    /// With --slurm: write the job script and print the sbatch command, without submitting
    #[arg(long)]
    pub dry_run: bool,
}

#[derive(Subcommand)]
pub enum SweepCommand {
    /// Join shards' outputs into one summary.json and summary.csv
    Merge(merge::MergeArgs),
}

/// Exit code after Ctrl-C (128 + SIGINT, as shells report it).
pub const EXIT_INTERRUPTED: u8 = 130;

/// Runs the sweep; returns the exit code (0 all completed, 1 a run failed, 2 bad input,
/// 130 interrupted).
pub fn run(args: &SweepArgs) -> Result<u8> {
    if let Some(SweepCommand::Merge(m)) = &args.command {
        return merge::run(m);
    }
    let plan = match plan(args) {
        Ok(p) => p,
        Err(problems) => {
            for p in problems {
                eprintln!("caravan: {p}");
            }
            return Ok(EXIT_BAD_INPUT);
        }
    };
    if let Some(options) = &args.slurm {
        return slurm::submit(&plan, args, options);
    }
    let prefix = group_prefix(&plan.name);
    let mut results: Vec<Vec<RunEntry>> = vec![Vec::new(); plan.cells.len()];
    let mut tasks = Vec::new();
    let mut total = 0;
    for (i, c, seed) in plan.runs() {
        if !plan.shard.has(i) {
            continue;
        }
        total += 1;
        let dir = plan.seed_dir(c, seed);
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
            args: launch_args(&plan, &plan.cells[c], seed, &dir, &group),
            dir,
            group,
        });
    }
    // Before any run: a shard that is killed still says what it was meant to run.
    manifest::Manifest::new(plan.definition(), plan.shard, plan.shard_runs()).write(&plan.out)?;
    let skipped = total - tasks.len();
    let part = if plan.shard == shard::Shard::ALL {
        String::new()
    } else {
        format!(", shard {} of them: {total}", plan.shard)
    };
    eprintln!(
        "caravan: sweep '{}': {} cells × {} seeds = {} runs{part} of {} into {}",
        plan.name,
        plan.cells.len(),
        plan.seeds.len(),
        plan.cells.len() * plan.seeds.len(),
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
        let seed_dir = plan.seed_dir(f.cell, f.seed);
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
    // A shard's summary would be one part of the sweep's: the merge writes the sweep's.
    let sharded = plan.shard != shard::Shard::ALL;
    let summary_json = plan.out.join("summary.json");
    let written = if sharded {
        format!(
            "shard {} done; when every shard is, summarise them with `caravan sweep merge {}`",
            plan.shard,
            plan.out.display()
        )
    } else {
        summary::write(&plan.out, &doc)?;
        format!("summary in {} and summary.csv", summary_json.display())
    };
    print!("{}", summary::table(&doc, &args.metric));
    for f in &failed {
        eprintln!("caravan: {f}");
    }
    let done: usize = results.iter().map(Vec::len).sum();
    let all_completed = results.iter().flatten().all(|r| r.outcome == "completed");
    if interrupted {
        eprintln!("caravan: interrupted; {done} of {total} runs finished; {written}");
        return Ok(EXIT_INTERRUPTED);
    }
    let not_completed = results
        .iter()
        .flatten()
        .filter(|r| r.outcome != "completed");
    eprintln!(
        "caravan: {} of {done} runs completed; {written}",
        done - not_completed.count(),
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
