//! Launching a group (`caravan launch FILE`): load and check the launch file, start the group
//! in a new run directory, supervise it until it ends, then write its facts and report.

use crate::report;
use crate::run::{self, output::Console};
use anyhow::{Context, Result};
use caravan_launch::LaunchError;
use caravan_launch::model::{EntryProblem, Exec, LaunchFile};
use caravan_report::ReportEntry;
use clap::Args;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct LaunchArgs {
    /// The launch file (TOML)
    pub file: PathBuf,
    /// Override a value of the launch file, e.g. `group.seed=3` or `process.ping.rate=20Hz`
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Run for this long (simulated time in lockstep), e.g. `30s`
    #[arg(long)]
    pub duration: Option<String>,
    /// Clock mode
    #[arg(long, value_parser = ["realtime", "lockstep"])]
    pub clock: Option<String>,
    /// Random seed of the group (0 to 9223372036854775807, the integers TOML holds)
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u64).range(..=i64::MAX as u64))]
    pub seed: Option<u64>,
    /// Directory that receives the run directory
    #[arg(long, default_value = "runs")]
    pub runs_dir: PathBuf,
    /// Do not echo process output to the terminal (it still goes to the logs)
    #[arg(long)]
    pub quiet: bool,
    /// Serve the running group to the Foxglove app (Open connection → Foxglove WebSocket,
    /// ws://127.0.0.1:PORT); PORT defaults to 8765, 0 picks a free one
    #[arg(long, value_name = "PORT", num_args = 0..=1, default_missing_value = "8765")]
    pub foxglove: Option<u16>,
    /// Play a recording's topics into the group, in the group's clock: each message at its
    /// recorded time (in lockstep, the simulated time it was published at); a rosbag2 bag of
    /// the types Caravan maps plays too
    #[arg(long, value_name = "FILE.mcap")]
    pub play: Option<PathBuf>,
    /// With --play: only these topics (names or patterns with *)
    #[arg(long, value_name = "TOPIC", num_args = 1.., requires = "play")]
    pub play_topics: Vec<String>,
    /// Start only these processes of the file (a recording played with --play stands in for
    /// the others)
    #[arg(long, value_name = "PROCESS", num_args = 1..)]
    pub only: Vec<String>,
    /// Run the part of the group on this host of `[hosts]`: start its processes only, and
    /// join the other hosts' launchers over zenoh (at the `listen` / `connect` endpoints of
    /// `[hosts]`); topics cross between hosts
    #[arg(long, value_name = "HOST")]
    pub host: Option<String>,
}

/// How to run a loaded launch file: the command line's options besides the file.
pub struct RunOptions {
    pub runs_dir: PathBuf,
    pub quiet: bool,
    pub foxglove: Option<u16>,
    pub play: Option<crate::play::InGroup>,
    pub only: Vec<String>,
    /// Run only this host's part, joined to the other hosts over zenoh.
    pub host: Option<String>,
    /// The command line the recording's `run` metadata keeps (`arguments`): the `caravan`
    /// command's, or what a program running the group in-process says it is.
    pub arguments: Vec<String>,
}

impl RunOptions {
    /// A run of the whole group on this machine, into a run directory under `runs_dir`, its
    /// output echoed to the terminal.
    pub fn new(runs_dir: impl Into<PathBuf>) -> Self {
        Self {
            runs_dir: runs_dir.into(),
            quiet: false,
            foxglove: None,
            play: None,
            only: Vec::new(),
            host: None,
            arguments: caravan_record::recorder::command_arguments(),
        }
    }
}

/// How a launch ended: the exit code, and the run directory if the group started.
pub struct Launched {
    pub code: u8,
    pub dir: Option<PathBuf>,
}

pub use crate::bad_input::EXIT_BAD_INPUT;
pub use crate::run::preflight::CheckMemo;

/// Loads and validates the launch file with the command line's overrides; see [`load_file`].
pub fn load(args: &LaunchArgs) -> Result<LaunchFile, LaunchError> {
    load_with(args, None)
}

/// [`load`], taking the outcome of checks already run on the same input from `memo` (a
/// sweep's cells share most of their processes' params).
pub fn load_with(args: &LaunchArgs, memo: Option<&CheckMemo>) -> Result<LaunchFile, LaunchError> {
    let mut sets = args.set.clone();
    if let Some(d) = &args.duration {
        sets.push(format!("group.duration={d}"));
    }
    if let Some(c) = &args.clock {
        sets.push(format!("group.clock={c}"));
    }
    if let Some(s) = args.seed {
        sets.push(format!("group.seed={s}"));
    }
    let check = |lf: &LaunchFile| check_entries(lf, memo);
    caravan_launch::load_checked(&args.file, &sets, &run::exec::resolve_exec, &check)
}

/// Loads and validates the launch file at `path` with `sets` (`KEY=VALUE`, as `--set` takes
/// them) applied, has every process check its params and inputs (`CARAVAN_CHECK=1`, see
/// [`run::preflight`]) and every report plugin its params (`PROGRAM --check`), so that
/// nothing bad gets started.
pub fn load_file(path: &Path, sets: &[String]) -> Result<LaunchFile, LaunchError> {
    let check = |lf: &LaunchFile| check_entries(lf, None);
    caravan_launch::load_checked(path, sets, &run::exec::resolve_exec, &check)
}

/// Every process's check of its input, then every report plugin's (`PROGRAM --check`).
fn check_entries(lf: &LaunchFile, memo: Option<&CheckMemo>) -> Vec<EntryProblem> {
    let mut problems = run::preflight::check_processes_with(lf, memo);
    for (index, entry) in report_entries(lf).iter().enumerate() {
        let checked = match memo {
            Some(memo) => memo.report(entry),
            None => report::check(entry),
        };
        if let Err(why) = checked {
            problems.push(run::preflight::report_problem(
                index,
                &entry.exec.join(" "),
                &entry.params,
                &why,
            ));
        }
    }
    problems
}

/// Runs the group; returns the process exit code.
pub fn launch(args: &LaunchArgs) -> Result<u8> {
    let lf = match load(args) {
        Ok(lf) => lf,
        Err(e) => {
            eprintln!("caravan: {e}");
            return Ok(EXIT_BAD_INPUT);
        }
    };
    // Runs go into a directory: a file there is bad input, found before anything starts.
    if let Some(why) = crate::bad_input::not_a_directory(&args.runs_dir) {
        eprintln!("caravan: --runs-dir {why}");
        return Ok(EXIT_BAD_INPUT);
    }
    let options = RunOptions {
        runs_dir: args.runs_dir.clone(),
        quiet: args.quiet,
        foxglove: args.foxglove,
        play: args.play.as_ref().map(|file| crate::play::InGroup {
            file: file.clone(),
            topics: args.play_topics.clone(),
            under_test: None,
        }),
        only: args.only.clone(),
        host: args.host.clone(),
        arguments: caravan_record::recorder::command_arguments(),
    };
    start(lf, &options).map(|l| l.code)
}

/// Leaves out the processes `keep` refuses, remembering where they would run.
fn keep_only(lf: &mut LaunchFile, keep: impl Fn(&caravan_launch::model::ProcessSpec) -> bool) {
    let (kept, left): (Vec<_>, Vec<_>) = std::mem::take(&mut lf.processes)
        .into_iter()
        .partition(|p| keep(p));
    lf.processes = kept;
    lf.left_out
        .extend(left.into_iter().map(|p| (p.name, p.host)));
}

/// Leaves out the processes `--host` and `only` do not name and adds the player of `play`; an error
/// names what the launch file lacks or the recording cannot give.
fn reshape(lf: &mut LaunchFile, options: &RunOptions) -> Result<()> {
    if let Some(host) = &options.host {
        caravan_bridge::check_host(lf, host)?;
        keep_only(lf, |p| &p.host == host);
    }
    if !options.only.is_empty() {
        let names: Vec<&str> = lf.processes.iter().map(|p| p.name.as_str()).collect();
        for name in &options.only {
            if !names.contains(&name.as_str()) {
                let hint = caravan_launch::suggest::hint(name, &names);
                anyhow::bail!(
                    "--only {name}: {} has no process '{name}'{hint}",
                    lf.path.display()
                );
            }
        }
        keep_only(lf, |p| options.only.contains(&p.name));
    }
    if let Some(play) = &options.play {
        let player = play.process(lf)?;
        lf.processes.push(player);
    }
    Ok(())
}

/// Runs a loaded launch file as `options` say.
pub fn start(mut lf: LaunchFile, options: &RunOptions) -> Result<Launched> {
    let console = Console::new(options.quiet);
    let bad = |e: anyhow::Error| {
        eprintln!("caravan: {e:#}");
        Ok(Launched {
            code: EXIT_BAD_INPUT,
            dir: None,
        })
    };
    if let Err(e) = reshape(&mut lf, options) {
        return bad(e);
    }
    let reports = report_entries(&lf);
    let group = lf.group.name.clone();
    // Before anything starts: a port already taken is bad input.
    let live = match options
        .foxglove
        .map(|port| caravan_record::live::LiveView::start(port, &group))
    {
        Some(Err(e)) => return bad(e),
        Some(Ok(live)) => Some(live),
        None => None,
    };
    let already = || {
        bad(anyhow::anyhow!(
            "group '{group}' is already running; stop it, or give this run another name with --set group.name=…"
        ))
    };
    // Held until the run ends: a second launch of the group gets the message above.
    let Some(_lock) = crate::clean::lock_group(&group)? else {
        return already();
    };
    // From here on a signal must not end the launcher before it removes the lock.
    let signals = crate::signals::Signals::watch()?;
    // Before this process first touches iceoryx2: its fallback config is the group's.
    let global = crate::clean::global_config_path(&group);
    caravan::group::write_config(&group, &global)
        .with_context(|| format!("cannot write {}", global.display()))?;
    caravan::group::use_as_global(&global)?;
    if crate::clean::group_is_running(&group)? {
        return already();
    }
    crate::clean::remove_stale(&group)?;
    // On several machines: nothing starts before every required host has joined.
    let mut bridge = match &options.host {
        Some(host) => {
            let bridge = caravan_bridge::Bridge::open(&lf, host)?;
            console.say(&format!("host '{host}' of group '{group}' is up"));
            let interrupter = bridge.interrupter();
            let (waited, signal) = signals.during(
                |signal| interrupter.interrupt(signal),
                || bridge.wait_for_hosts(lf.group.join_timeout, |m| console.say(m)),
            );
            // A signal that came as the last host joined stops the launch all the same.
            let waited = match (waited, signal) {
                (Ok(()), Some(signal)) => Err(caravan_bridge::Interrupted(signal).into()),
                (waited, _) => waited,
            };
            if let Err(e) = waited {
                eprintln!("caravan: {e:#}");
                bridge.close();
                // As a shell reports a command a signal stopped (and `caravan sweep` does).
                let code = match e.downcast_ref::<caravan_bridge::Interrupted>() {
                    Some(caravan_bridge::Interrupted(signal)) => 128 + *signal as u8,
                    None => 1,
                };
                return Ok(Launched { code, dir: None });
            }
            Some(bridge)
        }
        None => None,
    };
    let dir = run_dir(&options.runs_dir, &group)?;
    let resolved = dir.join("launch.toml");
    std::fs::write(&resolved, &lf.resolved_toml)
        .with_context(|| format!("cannot write {}", resolved.display()))?;
    let config_path = dir.join("iceoryx2.toml");
    caravan::group::write_config(&group, &config_path)
        .with_context(|| format!("cannot write {}", config_path.display()))?;
    std::fs::create_dir_all(dir.join("logs"))
        .with_context(|| format!("cannot create {}", dir.join("logs").display()))?;
    console.say(&format!(
        "group '{group}' ({} clock), run directory {}",
        lf.group.clock,
        dir.display()
    ));

    if let Some(live) = &live {
        console.say(&format!(
            "Foxglove live view on ws://{}:{} (Foxglove: Open connection → Foxglove WebSocket)",
            caravan_record::live::HOST,
            live.port()
        ));
    }
    let result = run::run_group(
        &lf,
        &dir,
        &config_path,
        live,
        bridge.as_mut(),
        &run::Launcher {
            console: &console,
            arguments: &options.arguments,
            signals: &signals,
        },
    )
    .map(|mut facts| {
        // The report plugins read the recording, which the clock host has.
        if facts.clock_host.is_none() {
            facts.reports = reports;
        }
        facts
    });
    if let Some(bridge) = bridge {
        bridge.close();
    }
    // Whatever happened, leave no shared memory of the group behind.
    let _ = caravan::group::remove_resources(&group);
    let facts = result?;
    let failed = facts.outcome == "failed";
    for w in &facts.warnings {
        eprintln!("caravan: warning: {w}");
    }
    facts.save(&dir)?;
    let written = report::write(&dir, options.quiet)?;
    for failure in &written.failures {
        console.say(failure);
    }
    let time = match &facts.clock_host {
        Some(clock) => format!(
            "ran {:.1} s (host '{clock}' kept simulated time and recorded)",
            facts.wall_time_s
        ),
        None => format!(
            "simulated {:.1} s in {:.1} s (real-time factor {:.2})",
            facts.sim_time_s,
            facts.wall_time_s,
            facts.real_time_factor()
        ),
    };
    // The run's outcome, and whether its report holds: the exit code says both.
    let plugins = match written.failures.len() {
        0 => "",
        1 => ", but a report plugin failed",
        _ => ", but report plugins failed",
    };
    console.say(&format!(
        "{}{plugins}: {time}; report in {}",
        facts.outcome,
        dir.join("report.md").display()
    ));
    Ok(Launched {
        code: if failed || !written.failures.is_empty() {
            1
        } else {
            0
        },
        dir: Some(dir),
    })
}

fn run_dir(base: &Path, group: &str) -> Result<PathBuf> {
    let stamp = chrono::Utc::now().format("%Y%m%d-%H%M%S");
    for n in 0.. {
        let name = if n == 0 {
            format!("{group}-{stamp}")
        } else {
            format!("{group}-{stamp}-{n}")
        };
        let dir = base.join(name);
        if !dir.exists() {
            std::fs::create_dir_all(&dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
            return Ok(dir);
        }
    }
    unreachable!()
}

/// The launch file's `[[report]]` entries, as the run's facts keep them.
fn report_entries(lf: &LaunchFile) -> Vec<ReportEntry> {
    lf.reports
        .iter()
        .map(|r| ReportEntry {
            exec: match &r.exec {
                Exec::Workspace(name) => vec![name.clone()],
                Exec::Command(words) => words.clone(),
            },
            params: r.params.clone(),
            launch_dir: r.launch_dir.display().to_string(),
            timeout_s: r.timeout.as_secs_f64(),
        })
        .collect()
}
