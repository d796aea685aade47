//! Running a group: start its processes with their environment, drive the lockstep
//! schedule or the realtime recorder, react to exits, signals and hangs until the group
//! ends, and collect what the run report needs.

pub mod driver;
mod events;
pub mod exec;
mod facts;
mod network;
pub mod output;
pub mod preflight;
mod robots;
pub mod supervisor;

use anyhow::Result;
use caravan::ClockMode;
use caravan_launch::model::{Exec, LaunchFile};
use caravan_record::RecordingMeta;
use caravan_report::RunFacts;
use crossbeam::channel::unbounded;
use driver::{Control, DriverConfig};
use output::Console;
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;
use supervisor::{Event, Planned, Supervisor};

/// The `run` metadata key naming the launch file.
pub const LAUNCH_FILE_KEY: &str = "launch_file";

fn plan(lf: &LaunchFile) -> Vec<Planned> {
    lf.processes
        .iter()
        .map(|spec| {
            let (program, mut args) = match &spec.exec {
                Exec::Workspace(name) => (exec::program(name, &spec.launch_dir), Vec::new()),
                Exec::Command(words) => (
                    exec::program(&words[0], &spec.launch_dir),
                    words[1..].to_vec(),
                ),
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
                members: Vec::new(),
            }
        })
        .collect()
}

/// What the launcher running a group lends it.
pub struct Launcher<'a> {
    /// Where progress is said.
    pub console: &'a Console,
    /// The command line after the program, for the recording's `run` metadata.
    pub arguments: &'a [String],
    /// Ctrl-C and SIGTERM, watched since the launcher took the group's lock.
    pub signals: &'a crate::signals::Signals,
}

/// Starts `lf`'s processes in run directory `dir`, supervises them until the group ends and
/// returns the run's facts (without its report plugins, which the caller adds).
pub fn run_group(
    lf: &LaunchFile,
    dir: &Path,
    config_path: &Path,
    live: Option<caravan_record::live::LiveView>,
    mut bridge: Option<&mut caravan_bridge::Bridge>,
    launcher: &Launcher,
) -> Result<RunFacts> {
    let &Launcher {
        console,
        arguments,
        signals,
    } = launcher;
    let lockstep = lf.group.clock == ClockMode::Lockstep;
    let (events_tx, events) = unbounded();
    let events_tx_for_bridge = events_tx.clone();
    let (finish_tx, finish_rx) = unbounded();
    let control = Arc::new(Control::default());
    let signals_tx = events_tx.clone();
    let received = signals.received();
    std::thread::spawn(move || {
        // Ends when the launcher stops watching, or the run's events are no longer read.
        for sig in received {
            if signals_tx.send(Event::Signal(sig)).is_err() {
                break;
            }
        }
    });
    // Lockstep across hosts: one host's launcher owns simulated time and records; the others
    // only run their processes.
    let clock_host = match &bridge {
        Some(_) if lockstep => Some(caravan_bridge::clock_host(lf)?),
        _ => None,
    };
    let follower = match (&clock_host, &bridge) {
        (Some(clock), Some(b)) => b.host() != clock,
        _ => false,
    };
    let mut sup = Supervisor::new(
        supervisor::containers(plan(lf), lockstep),
        environment(lf, dir, config_path)?,
        &dir.join("logs"),
        events_tx.clone(),
        console.clone(),
    )?;
    let iceoryx = caravan::group::load_config(config_path)?;
    let pending = (lockstep && !follower)
        .then(|| caravan::lockstep::Pending::create_or_warn(&iceoryx))
        .flatten();
    let driver = driver::spawn(
        DriverConfig {
            pending,
            group: lf.group.name.clone(),
            iceoryx,
            record_path: dir.join(caravan_report::RECORDING_FILE),
            // The clock host records the whole group.
            patterns: if follower {
                Vec::new()
            } else {
                lf.group.record.clone()
            },
            tick: lf.group.tick,
            spin: lf.group.spin,
            overlap: lf.group.overlap,
            // Across hosts a bridge forwards what a node publishes as it comes: a batch's
            // messages would reach the other hosts ahead of their time.
            batch: lf.group.batch && bridge.is_none(),
            duration: lf.group.duration,
            expected: {
                let mut names = sup.names();
                if let Some(b) = bridge.as_deref() {
                    // The scheduler waits for the processes of every host.
                    names.extend(
                        lf.left_out
                            .iter()
                            .filter(|(_, host)| *host != b.host())
                            .map(|(name, _)| name.clone()),
                    );
                }
                names
            },
            follower,
            step_timeout: lf.group.step_timeout,
            join_timeout: lf.group.join_timeout,
            reporting: plan(lf)
                .iter()
                .filter(|p| preflight::is_checked(p))
                .map(|p| p.spec.name.clone())
                .collect(),
            live,
            meta: RecordingMeta {
                metadata: {
                    let mut m = caravan_record::recorder::run_metadata(
                        arguments,
                        Some(lf.group.seed),
                        (!lockstep).then(caravan::wall_clock_ns),
                    );
                    // As given on the command line: `caravan resim` finds the directory the
                    // attached launch file's relative paths start from by it.
                    m.insert(LAUNCH_FILE_KEY.into(), lf.path.display().to_string());
                    m
                },
                launch_file: Some(lf.resolved_toml.clone().into_bytes()),
            },
        },
        lockstep,
        control.clone(),
        events_tx,
        finish_rx,
    );
    if let Some(bridge) = bridge.as_deref_mut() {
        bridge.attach(
            Box::new(move |e| {
                let _ = events_tx_for_bridge.send(Event::Fleet(e));
            }),
            &caravan::group::load_config(config_path)?,
            caravan_bridge::remote_nodes(lf),
            clock_host.clone(),
            dir,
        )?;
    }
    let started = Instant::now();
    sup.start_all()?;
    let ending = events::supervise(
        lf,
        &mut sup,
        &events,
        &control,
        console,
        started,
        bridge.as_deref(),
    );
    sup.kill_leftovers();
    let ending = ending?;
    let wall_time_s = started.elapsed().as_secs_f64();
    let _ = finish_tx.send(());
    let driven = driver
        .join()
        .map_err(|_| anyhow::anyhow!("the driver thread panicked"))??;
    let mut facts = facts::collect(lf, ending, sup.records(), driven, wall_time_s);
    if follower {
        facts.clock_host = clock_host;
    }
    Ok(facts)
}

/// What every process of the group finds in its environment (each adds its own name,
/// host, params…).
fn environment(
    lf: &LaunchFile,
    dir: &Path,
    config_path: &Path,
) -> Result<BTreeMap<String, String>> {
    let mut env = group_environment(lf)?;
    env.insert(
        caravan::env_vars::ICEORYX_CONFIG.to_string(),
        std::path::absolute(config_path)?.display().to_string(),
    );
    env.insert(
        caravan::env_vars::RUN_DIR.to_string(),
        std::path::absolute(dir)?.display().to_string(),
    );
    env.insert(
        caravan::env_vars::EPOCH_NS.to_string(),
        caravan::wall_clock_ns().to_string(),
    );
    Ok(env)
}

/// The part of [`environment`] that does not depend on the run: what a process's check sees.
fn group_environment(lf: &LaunchFile) -> Result<BTreeMap<String, String>> {
    let mut env = BTreeMap::new();
    env.insert(caravan::env_vars::GROUP.to_string(), lf.group.name.clone());
    env.insert(
        caravan::env_vars::CLOCK.to_string(),
        lf.group.clock.to_string(),
    );
    env.insert(
        caravan::env_vars::SEED.to_string(),
        lf.group.seed.to_string(),
    );
    if !lf.group.spin.is_zero() {
        env.insert(
            caravan::env_vars::SPIN.to_string(),
            caravan::spin::spin_text(lf.group.spin),
        );
    }
    if let Some(net) = network::resolve(lf) {
        env.insert(
            caravan::env_vars::NETWORK.to_string(),
            serde_json::to_string(&net)?,
        );
    }
    Ok(env)
}
