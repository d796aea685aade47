//! `caravan launch`: start a group from a launch file, supervise it, record it, report it.

pub mod driver;
mod network;
pub mod output;
pub mod supervisor;

use crate::launch::model::{Exec, LaunchFile};
use crate::report;
use anyhow::{Context, Result};
use caravan::ClockMode;
use caravan_report::{HostFacts, Latency, ReportEntry, RunFacts};
use clap::Args;
use crossbeam::channel::{RecvTimeoutError, unbounded};
use driver::{Control, DriverConfig};
use output::Console;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::Instant;
use supervisor::{Event, Planned, Supervisor};

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
    /// Random seed of the group
    #[arg(long)]
    pub seed: Option<u64>,
    /// Directory that receives the run directory
    #[arg(long, default_value = "runs")]
    pub runs_dir: PathBuf,
    /// Do not echo process output to the terminal (it still goes to the logs)
    #[arg(long)]
    pub quiet: bool,
}

/// Exit code for bad input: nothing was started.
pub const EXIT_BAD_INPUT: u8 = 2;

/// Where a bare executable name is found: beside the `caravan` binary (the workspace's
/// target directory), then on PATH.
pub fn resolve_exec(name: &str) -> Option<PathBuf> {
    let beside = std::env::current_exe().ok()?.parent()?.join(name);
    if beside.is_file() {
        return Some(beside);
    }
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|dir| dir.join(name))
            .find(|p| p.is_file())
    })
}

/// Loads and validates the launch file with the command line's overrides.
pub fn load(args: &LaunchArgs) -> Result<LaunchFile, crate::launch::load::LaunchError> {
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
    crate::launch::load::load(&args.file, &sets, &resolve_exec)
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

fn plan(lf: &LaunchFile) -> Vec<Planned> {
    lf.processes
        .iter()
        .map(|spec| {
            let (program, mut args) = match &spec.exec {
                Exec::Workspace(name) => (
                    resolve_exec(name).unwrap_or_else(|| PathBuf::from(name)),
                    Vec::new(),
                ),
                Exec::Command(words) => {
                    let first = &words[0];
                    let program = if first.contains('/') {
                        // Relative to the file that defined the process (absolute).
                        spec.launch_dir.join(first)
                    } else {
                        resolve_exec(first).unwrap_or_else(|| PathBuf::from(first))
                    };
                    (program, words[1..].to_vec())
                }
            };
            args.extend(spec.args.iter().cloned());
            // Relative paths in params (worlds, robot descriptions) are relative to the file
            // that defined the process, which may be an included one; the process's own env
            // may still say otherwise.
            let mut spec = spec.clone();
            spec.env
                .entry(caravan::env_vars::LAUNCH_DIR.to_string())
                .or_insert_with(|| spec.launch_dir.display().to_string());
            Planned {
                spec,
                program,
                args,
            }
        })
        .collect()
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
        })
        .collect()
}

/// Runs the group; returns the process exit code.
pub fn launch(args: &LaunchArgs) -> Result<u8> {
    let console = Console::new(args.quiet);
    let lf = match load(args) {
        Ok(lf) => lf,
        Err(e) => {
            eprintln!("caravan: {e}");
            return Ok(EXIT_BAD_INPUT);
        }
    };
    // Report plugins check their params now, so bad ones start nothing.
    let reports = report_entries(&lf);
    for entry in &reports {
        if let Err(why) = report::check(entry) {
            eprintln!(
                "caravan: {}: report '{}': {why}",
                lf.path.display(),
                entry.exec.join(" ")
            );
            return Ok(EXIT_BAD_INPUT);
        }
    }
    let group = lf.group.name.clone();
    if crate::clean::group_is_running(&group)? {
        eprintln!(
            "caravan: group '{group}' is already running; stop it, or give this run another name with --set group.name=…"
        );
        return Ok(EXIT_BAD_INPUT);
    }
    crate::clean::remove_stale(&group)?;
    let dir = run_dir(&args.runs_dir, &group)?;
    std::fs::write(dir.join("launch.toml"), &lf.resolved_toml)?;
    let config_path = dir.join("iceoryx2.toml");
    caravan::group::write_config(&group, &config_path)?;
    std::fs::create_dir_all(dir.join("logs"))?;
    console.say(&format!(
        "group '{group}' ({} clock), run directory {}",
        lf.group.clock,
        dir.display()
    ));

    let result = run_group(&lf, &dir, &config_path, &console).map(|mut facts| {
        facts.reports = reports;
        facts
    });
    // Whatever happened, leave no shared memory of the group behind.
    let _ = caravan::group::remove_resources(&group);
    let facts = result?;
    let failed = facts.outcome == "failed";
    facts.save(&dir)?;
    let written = report::write(&dir)?;
    for failure in &written.failures {
        console.say(failure);
    }
    console.say(&format!(
        "{}: simulated {:.1} s in {:.1} s (real-time factor {:.2}); report in {}",
        facts.outcome,
        facts.sim_time_s,
        facts.wall_time_s,
        facts.real_time_factor(),
        dir.join("report.md").display()
    ));
    Ok(if failed || !written.failures.is_empty() {
        1
    } else {
        0
    })
}

fn run_group(
    lf: &LaunchFile,
    dir: &Path,
    config_path: &Path,
    console: &Console,
) -> Result<RunFacts> {
    let lockstep = lf.group.clock == ClockMode::Lockstep;
    let (events_tx, events) = unbounded();
    let (finish_tx, finish_rx) = unbounded();
    let control = Arc::new(Control::default());
    let signals_tx = events_tx.clone();
    let mut signals = signal_hook::iterator::Signals::new([
        signal_hook::consts::SIGINT,
        signal_hook::consts::SIGTERM,
    ])?;
    let signals_handle = signals.handle();
    std::thread::spawn(move || {
        for sig in signals.forever() {
            let _ = signals_tx.send(Event::Signal(sig));
        }
    });

    let mut env = BTreeMap::new();
    env.insert(caravan::env_vars::GROUP.to_string(), lf.group.name.clone());
    env.insert(
        caravan::env_vars::ICEORYX_CONFIG.to_string(),
        std::path::absolute(config_path)?.display().to_string(),
    );
    env.insert(
        caravan::env_vars::CLOCK.to_string(),
        lf.group.clock.to_string(),
    );
    env.insert(
        caravan::env_vars::SEED.to_string(),
        lf.group.seed.to_string(),
    );
    if let Some(net) = network::resolve(lf) {
        env.insert(
            caravan::env_vars::NETWORK.to_string(),
            serde_json::to_string(&net)?,
        );
    }
    env.insert(
        caravan::env_vars::RUN_DIR.to_string(),
        std::path::absolute(dir)?.display().to_string(),
    );
    env.insert(
        caravan::env_vars::EPOCH_NS.to_string(),
        caravan::wall_clock_ns().to_string(),
    );
    let mut sup = Supervisor::new(
        plan(lf),
        env,
        &dir.join("logs"),
        events_tx.clone(),
        console.clone(),
    )?;

    let driver = driver::spawn(
        DriverConfig {
            iceoryx: caravan::group::load_config(config_path)?,
            record_path: dir.join(caravan_report::RECORDING_FILE),
            patterns: lf.group.record.clone(),
            tick: lf.group.tick,
            duration: lf.group.duration,
            expected: sup.names(),
            step_timeout: lf.group.step_timeout,
        },
        lockstep,
        control.clone(),
        events_tx,
        finish_rx,
    );
    let started = Instant::now();
    sup.start_all()?;

    let wall_deadline = if lockstep {
        None
    } else {
        lf.group.duration.map(|d| started + d)
    };
    let mut next_restart: Option<Instant> = None;
    let mut kill_at: Option<Instant> = None;
    let (mut outcome, mut failure) = ("completed", None::<String>);
    let mut stopping = false;
    let begin_stop = |sup: &mut Supervisor, stopping: &mut bool, kill_at: &mut Option<Instant>| {
        if !*stopping {
            *stopping = true;
            control.stop.store(true, Ordering::Relaxed);
            sup.signal_all(libc::SIGTERM);
            *kill_at = Some(Instant::now() + lf.group.grace);
        }
    };
    loop {
        if stopping && !sup.any_alive() {
            break;
        }
        let deadline = [next_restart, wall_deadline.filter(|_| !stopping), kill_at]
            .into_iter()
            .flatten()
            .min();
        let event = match deadline {
            Some(d) => events.recv_timeout(d.saturating_duration_since(Instant::now())),
            None => events.recv().map_err(|_| RecvTimeoutError::Disconnected),
        };
        match event {
            Ok(Event::Exited {
                index,
                generation,
                status,
                usage,
                last_error,
            }) => {
                let name = sup.names()[index].clone();
                control.deaths.lock().unwrap().push(name);
                match sup.on_exit(index, generation, status, usage, &last_error, stopping) {
                    Ok(Some(at)) => next_restart = Some(next_restart.map_or(at, |n| n.min(at))),
                    Ok(None) => {}
                    Err(why) => {
                        console.say(&why);
                        (outcome, failure) = ("failed", Some(why));
                        begin_stop(&mut sup, &mut stopping, &mut kill_at);
                    }
                }
                if !stopping && sup.all_done() {
                    begin_stop(&mut sup, &mut stopping, &mut kill_at);
                }
            }
            Ok(Event::Signal(sig)) => {
                if stopping {
                    // A second Ctrl-C: do not wait for the grace period.
                    sup.signal_all(libc::SIGKILL);
                } else {
                    console.say(&format!("stopping the group (signal {sig})"));
                    outcome = "interrupted";
                    begin_stop(&mut sup, &mut stopping, &mut kill_at);
                }
            }
            Ok(Event::Hung {
                names,
                now_ns,
                timeout,
            }) => {
                for name in names {
                    console.say(&format!(
                        "process '{name}' has not finished a step at {:.3} s for {timeout:?} (step_timeout); it looks hung, killing it",
                        now_ns as f64 * 1e-9
                    ));
                    sup.kill(&name);
                }
            }
            Ok(Event::DriverDone(result)) => {
                if let Err(why) = result {
                    console.say(&why);
                    (outcome, failure) = ("failed", Some(why));
                }
                begin_stop(&mut sup, &mut stopping, &mut kill_at);
            }
            Err(RecvTimeoutError::Timeout) => {
                let now = Instant::now();
                if kill_at.is_some_and(|k| k <= now) {
                    console.say("grace period over; killing the remaining processes");
                    sup.signal_all(libc::SIGKILL);
                    kill_at = None;
                }
                if wall_deadline.is_some_and(|d| d <= now) && !stopping {
                    begin_stop(&mut sup, &mut stopping, &mut kill_at);
                }
                if next_restart.is_some_and(|r| r <= now) && !stopping {
                    next_restart = sup.restart_due(now)?;
                }
            }
            Err(RecvTimeoutError::Disconnected) => break,
        }
    }
    let wall_time_s = started.elapsed().as_secs_f64();
    signals_handle.close();
    let _ = finish_tx.send(());
    let outcome_of_driver = driver
        .join()
        .map_err(|_| anyhow::anyhow!("the driver thread panicked"))?;
    let driven = outcome_of_driver?;
    let recording = driven.recording;
    let sim_time_s = if lockstep {
        driven.sim_time_ns as f64 / 1e9
    } else {
        wall_time_s
    };
    let topic_latency = recording
        .topics
        .iter()
        .map(|(name, s)| {
            let q = |q: f64| s.latency.value_at_quantile(q) as f64 / 1e3;
            (
                name.clone(),
                Latency {
                    p50: q(0.5),
                    p90: q(0.9),
                    p99: q(0.99),
                    max: s.latency.max() as f64 / 1e3,
                },
            )
        })
        .collect();
    let topic_types = recording
        .topics
        .iter()
        .map(|(n, s)| (n.clone(), s.type_name.clone()))
        .collect();
    Ok(RunFacts {
        group: lf.group.name.clone(),
        clock: lf.group.clock.to_string(),
        seed: lf.group.seed,
        launch_file: lf.path.display().to_string(),
        outcome: outcome.to_string(),
        failure,
        sim_time_s,
        wall_time_s,
        processes: sup.records(),
        node_status: recording.node_status,
        topic_latency,
        topic_types,
        hosts: lf
            .hosts
            .iter()
            .map(|(name, h)| {
                let facts = HostFacts {
                    cpu_slowdown: h.cpu_slowdown,
                };
                (name.clone(), facts)
            })
            .collect(),
        reports: Vec::new(),
    })
}
