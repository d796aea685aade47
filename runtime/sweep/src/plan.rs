//! The plan of a sweep: the target and the command line read into cells × seeds, every cell
//! validated as `caravan launch` would before anything starts.

use super::SweepArgs;
use super::file;
use super::grid::{self, Axis, Cell};
use super::manifest::{Definition, RunRef};
use super::shard::{self, Shard};
use caravan_group::launch::{CheckMemo, LaunchArgs};
use caravan_launch::LaunchError;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The most cells a sweep takes: each is at least one group run, and every cell is validated
/// before anything starts (a few milliseconds each), so more is a mistake.
pub const MAX_CELLS: usize = 100_000;

/// From this many cells on, checking them shows a progress line (about a second's work).
const PROGRESS_FROM: usize = 200;

/// Without a terminal for the progress bar (a log, a batch job), how often a line says how far
/// the check is.
const PROGRESS_EVERY: Duration = Duration::from_secs(10);

/// Everything the sweep will do, checked before anything runs.
pub struct Plan {
    pub name: String,
    pub launch: PathBuf,
    /// FNV-1a of the launch file's bytes, in hex.
    pub launch_hash: String,
    pub seeds: Vec<u64>,
    /// Overrides of every run: the sweep file's, then the command line's.
    pub sets: Vec<String>,
    pub axes: Vec<Axis>,
    pub cells: Vec<Cell>,
    pub jobs: usize,
    /// Whether `--jobs` (or the sweep file) chose `jobs`, rather than the core count.
    pub jobs_given: bool,
    pub out: PathBuf,
    pub duration: Option<String>,
    /// The part of the runs this process runs (all of them unless `--shard`).
    pub shard: Shard,
}

impl Plan {
    /// The `--set`s of one run of `cell`. The cell's come after the common ones and the
    /// sweep's group name last, so every concurrent group has its own name.
    pub fn sets(&self, cell: &Cell, group: &str) -> Vec<String> {
        let mut sets = self.sets.clone();
        sets.extend(cell.sets.iter().cloned());
        sets.push(format!("group.name={group}"));
        sets
    }

    /// Every run in the canonical order, seed-major (every cell's first seed, then every
    /// cell's second…), so that an interrupted sweep has every cell's first seeds: (index in
    /// that order, cell index, seed). Shards are cut from this order.
    pub fn runs(&self) -> impl Iterator<Item = (usize, usize, u64)> + '_ {
        let n = self.cells.len();
        self.seeds
            .iter()
            .enumerate()
            .flat_map(move |(s, &seed)| (0..n).map(move |c| (s * n + c, c, seed)))
    }

    /// The run directory of `cell` and `seed`: `<out>/runs/<cell-id>/seed-<s>`.
    pub fn seed_dir(&self, cell: usize, seed: u64) -> PathBuf {
        self.out
            .join("runs")
            .join(&self.cells[cell].id)
            .join(format!("seed-{seed}"))
    }

    /// What identifies this sweep, for the shards' manifests.
    pub fn definition(&self) -> Definition {
        Definition {
            name: self.name.clone(),
            launch: self.launch.clone(),
            launch_hash: self.launch_hash.clone(),
            seeds: self.seeds.clone(),
            sets: self.sets.clone(),
            duration: self.duration.clone(),
            axes: self.axes.clone(),
        }
    }

    /// The runs of this plan's shard, for its manifest.
    pub fn shard_runs(&self) -> Vec<RunRef> {
        self.runs()
            .filter(|&(i, _, _)| self.shard.has(i))
            .map(|(_, c, seed)| RunRef {
                cell: self.cells[c].id.clone(),
                seed,
            })
            .collect()
    }
}

/// The start of the sweep's group names: `<name>-<pid>-<n>` must fit in 40 characters of
/// [A-Za-z0-9-] and differ from every other sweep's, hence the pid.
pub fn group_prefix(name: &str) -> String {
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
pub fn plan(args: &SweepArgs) -> Result<Plan, Vec<String>> {
    let Some(target) = &args.target else {
        return Err(vec!["no launch file or sweep file given".into()]);
    };
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
        Some(spec) => caravan_report::seeds::parse(spec).unwrap_or_else(|e| {
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
    let shard = match &args.shard {
        Some(text) => shard::parse(text, |name| std::env::var(name).ok()).unwrap_or_else(|e| {
            problems.push(e);
            Shard::ALL
        }),
        None => Shard::ALL,
    };
    let cells = (sweep.axes.iter()).fold(1usize, |n, a| n.saturating_mul(a.values.len()));
    if cells > MAX_CELLS {
        let sizes: Vec<String> = sweep
            .axes
            .iter()
            .map(|a| a.values.len().to_string())
            .collect();
        // The product saturates: past usize::MAX, the sizes say what the count would be.
        let count = if cells == usize::MAX {
            String::new()
        } else {
            format!(" = {cells}")
        };
        problems.push(format!(
            "the grid has {}{count} cells, more than the {MAX_CELLS} a sweep takes; nothing \
             was checked or run",
            sizes.join(" × ")
        ));
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let jobs_given = args.jobs.or(sweep.jobs).is_some();
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
    let launch_hash = std::fs::read(&sweep.launch)
        .map(|bytes| format!("{:016x}", grid::fnv(&bytes)))
        .unwrap_or_default();
    let plan = Plan {
        name: sweep.name,
        launch: sweep.launch,
        launch_hash,
        seeds,
        sets,
        cells: grid::expand(&sweep.axes),
        axes: sweep.axes,
        jobs,
        jobs_given,
        out,
        duration: args.duration.clone(),
        shard,
    };
    let problems = validate(&plan, args.quiet);
    if problems.is_empty() {
        Ok(plan)
    } else {
        Err(problems)
    }
}

/// `text` with each `--set` that a sweep file's axis value wrote followed by where the file
/// wrote it: `--set process.ping.rate=fast (sweep.toml:7)`.
fn with_origins(mut text: String, axes: &[Axis], cell: &Cell) -> String {
    for (axis, label) in &cell.values {
        let value = axes
            .iter()
            .find(|a| &a.label == axis)
            .and_then(|a| a.values.iter().find(|v| &v.label == label));
        let Some(value) = value else { continue };
        let Some(origin) = &value.origin else {
            continue;
        };
        for set in &value.sets {
            let said = format!("--set {set}");
            if let Some(at) = text.find(&said) {
                text.insert_str(at + said.len(), &format!(" ({origin})"));
            }
        }
    }
    text
}

/// Loads the launch file with every cell's overrides, as `caravan launch` would, without
/// starting anything. A problem shared by several cells is reported once, naming them. A shard
/// checks only the cells it runs (the submitting `--slurm` checked them all).
fn validate(plan: &Plan, quiet: bool) -> Vec<String> {
    // The output must be a directory (made, or resumed); a file there is bad input.
    if let Some(why) = caravan_group::bad_input::not_a_directory(&plan.out) {
        return vec![format!("--out {why}")];
    }
    let mut problems: Vec<(String, Vec<&str>)> = Vec::new();
    let mut mine = vec![false; plan.cells.len()];
    for (i, c, _) in plan.runs() {
        mine[c] |= plan.shard.has(i);
    }
    // Each cell takes milliseconds: a big grid says what it is doing, and how far it is.
    let count = mine.iter().filter(|m| **m).count();
    let progress = !quiet && count >= PROGRESS_FROM;
    let bar = if !progress {
        ProgressBar::hidden()
    } else {
        eprintln!(
            "caravan: checking {count} cells as `caravan launch` would, before anything starts"
        );
        ProgressBar::new(count as u64).with_style(
            ProgressStyle::with_template("{bar:30} {pos}/{len} cells checked, ETA {eta}")
                .expect("valid template"),
        )
    };
    // Without a terminal the bar draws nothing: a plain line now and then says how far it is.
    let lines = progress && !std::io::stderr().is_terminal();
    let mut said = Instant::now();
    // Cells mostly differ in one process's params: the others' checks are run once.
    let memo = CheckMemo::default();
    for (done, (cell, _)) in plan
        .cells
        .iter()
        .zip(&mine)
        .filter(|(_, m)| **m)
        .enumerate()
    {
        bar.inc(1);
        if lines && said.elapsed() >= PROGRESS_EVERY {
            eprintln!("caravan: checked {done} of {count} cells");
            said = Instant::now();
        }
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
        match caravan_group::launch::load_with(&args, Some(&memo)) {
            Ok(_) => {}
            Err(e @ LaunchError::Read { .. }) => return vec![e.to_string()],
            Err(LaunchError::Invalid(list)) => {
                for p in list {
                    let text = with_origins(p.to_string(), &plan.axes, cell);
                    match problems.iter_mut().find(|(t, _)| *t == text) {
                        Some((_, cells)) => cells.push(&cell.id),
                        None => problems.push((text, vec![&cell.id])),
                    }
                }
            }
        }
    }
    bar.finish_and_clear();
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
