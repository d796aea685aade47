//! The launcher's driver thread: in lockstep it owns simulated time (the scheduler) and drains
//! the recorder after every advance; in realtime it records as messages arrive.

use super::supervisor::Event;
use anyhow::{Result, anyhow};
use caravan::discovery::{discovery_interval, listen_until};
use caravan_lockstep::Scheduler;
use caravan_record::{Recorder, Recording, RecordingMeta};
use crossbeam::channel::{Receiver, Sender};
use iceoryx2::prelude::*;
use std::collections::BTreeSet;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Shared between the launcher's main loop and the driver thread.
#[derive(Default)]
pub struct Control {
    /// The group is stopping: stop scheduling.
    pub stop: AtomicBool,
    /// Processes that died since the driver last looked.
    pub deaths: Mutex<Vec<String>>,
}

pub struct DriverConfig {
    pub group: String,
    pub iceoryx: iceoryx2::config::Config,
    pub record_path: PathBuf,
    pub patterns: Vec<String>,
    pub tick: Duration,
    /// Lockstep: how long the scheduler spins for a report before it sleeps.
    pub spin: Duration,
    /// Lockstep: let the next tick's nodes overlap the current one's (see `GroupSpec`).
    pub overlap: bool,
    /// Lockstep: grant a periodic node several periods at once when none of its inputs can
    /// change meanwhile (see `GroupSpec`).
    pub batch: bool,
    pub duration: Option<Duration>,
    /// Processes that must join the lockstep schedule.
    pub expected: Vec<String>,
    /// Lockstep across hosts, on a host other than the clock host: its scheduler steps this
    /// host's nodes from there, and records them there.
    pub follower: bool,
    /// Wall time a lockstep step may take before the node is deemed hung.
    pub step_timeout: Duration,
    /// Wall time the processes have to join the lockstep schedule, or in realtime to publish
    /// their first status.
    pub join_timeout: Duration,
    /// Realtime: the processes that are Caravan nodes, which publish a status once a second.
    pub reporting: Vec<String>,
    /// The live view, if `--foxglove` asked for one.
    pub live: Option<caravan_record::live::LiveView>,
    /// The recording's metadata and attachment.
    pub meta: RecordingMeta,
    /// Lockstep, on the host that owns time: the count of quiet steps, made before any
    /// process starts so that every node finds it when it joins (`caravan::lockstep::Pending`).
    pub pending: Option<caravan::lockstep::Pending>,
}

/// What the driver reports when it ends.
pub struct DriverOutcome {
    pub recording: Recording,
    pub sim_time_ns: u64,
    /// Lockstep: what the scheduler did.
    pub schedule: Option<caravan_lockstep::ScheduleStats>,
}

/// Runs the driver on its own thread (iceoryx2 ports stay on the thread that made them).
/// It sends `Event::DriverDone` when the schedule ends, then waits for `finish` (all
/// processes exited) to drain the last messages and close the recording.
pub fn spawn(
    mut cfg: DriverConfig,
    lockstep: bool,
    control: Arc<Control>,
    events: Sender<Event>,
    finish: Receiver<()>,
) -> std::thread::JoinHandle<Result<DriverOutcome>> {
    // Named, so that a profile tells the scheduler's thread from the launcher's others.
    let driver = std::thread::Builder::new().name("driver".into());
    let spawned = driver.spawn(move || {
        let mut recorder = Recorder::create(
            &cfg.iceoryx,
            &cfg.record_path,
            &cfg.patterns,
            lockstep,
            &cfg.meta,
        )?;
        if let Some(live) = cfg.live.take() {
            recorder.serve(live)?;
        }
        // The recorder's node made the group's global files; keep them to this user.
        caravan::group::make_private(&cfg.group);
        let (sim_time_ns, schedule) = if lockstep && cfg.follower {
            // Only the nodes' statuses, for this host's report.
            record_until(
                &cfg.iceoryx,
                &mut recorder,
                SignalHandlingMode::Disabled,
                |_| finish.try_recv().is_ok(),
            )?;
            (0, None)
        } else if lockstep {
            let (end, stats) = run_lockstep(&mut cfg, &mut recorder, &control, &events, &finish)?;
            (end, Some(stats))
        } else {
            let started = Instant::now();
            let mut reported = BTreeSet::new();
            let mut awaited = cfg.reporting.clone();
            record_until(
                &cfg.iceoryx,
                &mut recorder,
                SignalHandlingMode::Disabled,
                |recorder| {
                    // A node silent for longer than the step timeout is reported once as hung.
                    let silent: Vec<String> = recorder
                        .silent_nodes(cfg.step_timeout)
                        .into_iter()
                        .filter(|n| reported.insert(n.clone()))
                        .collect();
                    if !silent.is_empty() {
                        let now_ns = started.elapsed().as_nanos() as u64;
                        let _ = events.send(Event::Hung {
                            names: silent,
                            now_ns,
                            timeout: cfg.step_timeout,
                        });
                    }
                    // A Caravan node that never published a status is as stuck as a hung one.
                    if !awaited.is_empty() && started.elapsed() > cfg.join_timeout {
                        let names: Vec<String> = std::mem::take(&mut awaited)
                            .into_iter()
                            .filter(|n| !recorder.has_reported(n))
                            .collect();
                        if !names.is_empty() {
                            let _ = events.send(Event::Silent {
                                names,
                                timeout: cfg.join_timeout,
                            });
                        }
                    }
                    finish.try_recv().is_ok()
                },
            )?;
            (started.elapsed().as_nanos() as u64, None)
        };
        Ok(DriverOutcome {
            recording: recorder.finish()?,
            sim_time_ns,
            schedule,
        })
    });
    spawned.expect("the launcher can start a thread")
}

/// Advances between two drains of every tap in lockstep (else only the published topics').
const FULL_DRAIN_EVERY: u64 = 100;

fn run_lockstep(
    cfg: &mut DriverConfig,
    recorder: &mut Recorder,
    control: &Control,
    events: &Sender<Event>,
    finish: &Receiver<()>,
) -> Result<(u64, caravan_lockstep::ScheduleStats)> {
    let mut scheduler = Scheduler::with_pending(&cfg.iceoryx, cfg.tick, cfg.pending.take())?;
    scheduler.set_spin(cfg.spin);
    // A node that died in its step never reported what it published: the next drain looks
    // at every tap.
    let died = std::cell::Cell::new(false);
    let watchdog = |_: &[&str]| {
        if control.stop.load(Ordering::Relaxed) {
            return Err("the group is stopping".to_string());
        }
        let deaths = std::mem::take(&mut *control.deaths.lock().unwrap());
        if !deaths.is_empty() {
            died.set(true);
        }
        Ok(deaths)
    };
    let end_ns = cfg.duration.map(|d| d.as_nanos() as u64);
    let mut now_ns = 0;
    let mut advances: u64 = 0;
    let result = (|| -> Result<()> {
        let waiting_since = Instant::now();
        scheduler.wait_for_nodes(&cfg.expected, |missing: &[&str]| {
            if waiting_since.elapsed() > cfg.join_timeout {
                return Err(format!(
                    "not joined after {:?} (join_timeout); a lockstep process must be a Caravan node, \
                     or run the group with clock = \"realtime\"",
                    cfg.join_timeout
                ));
            }
            watchdog(missing)
        })?;
        recorder.discover()?;
        scheduler.know_topics(recorder.seen());
        if cfg.overlap {
            scheduler.overlap_until(end_ns.unwrap_or(u64::MAX));
        }
        if cfg.batch {
            scheduler.batch_until(end_ns.unwrap_or(u64::MAX));
        }
        let longest_grant = scheduler.longest_grant();
        while let Some(next) = scheduler.next_time_ns() {
            if end_ns.is_some_and(|end| next > end) {
                break;
            }
            // A node that does not finish its step in time is reported once, as hung; the
            // launcher kills it and the wait ends with its death.
            let started = Instant::now();
            let mut reported = false;
            let hang_watch = |waiting: &[&str]| {
                // A node granted several periods at once has the time of each.
                let steps = longest_grant.get().clamp(1, u32::MAX as u64) as u32;
                if !reported && started.elapsed() > cfg.step_timeout.saturating_mul(steps) {
                    reported = true;
                    let names = waiting.iter().map(|n| n.to_string()).collect();
                    let _ = events.send(Event::Hung {
                        names,
                        now_ns: next,
                        timeout: cfg.step_timeout.saturating_mul(steps),
                    });
                }
                watchdog(waiting)
            };
            let Some(advance) = scheduler.advance(hang_watch)? else {
                break;
            };
            now_ns = advance.now_ns;
            let discovered = recorder.has_unseen(&advance.published);
            if discovered {
                recorder.discover()?;
                scheduler.know_topics(recorder.seen());
            }
            advances += 1;
            // A topic is looked at when a node said it published there. All of them are, at
            // the first advance (a node may publish while it starts, before it joins), when
            // discovery found new topics, after a node died, and once every
            // `FULL_DRAIN_EVERY` advances (a publisher outside the schedule).
            if discovered || died.replace(false) || advances % FULL_DRAIN_EVERY == 1 {
                recorder.drain_except(&advance.overlapping, now_ns)?;
            } else {
                recorder.drain_published(&advance.published, &advance.overlapping, now_ns)?;
            }
        }
        Ok(())
    })();
    // Being stopped from outside (Ctrl-C, a failed process) is not the scheduler's failure.
    let result = result.or_else(|e| {
        if control.stop.load(Ordering::Relaxed) {
            Ok(())
        } else {
            Err(e)
        }
    });
    let _ = events.send(Event::DriverDone(
        result.as_ref().map(|_| ()).map_err(|e| format!("{e:#}")),
    ));
    scheduler.stop_all()?;
    let _ = finish.recv();
    Ok((now_ns, scheduler.stats()))
}

/// Records as messages arrive, woken by the topics' listeners, until `done()` or (with
/// `signals` handling termination requests) Ctrl-C.
pub fn record_until(
    iceoryx: &iceoryx2::config::Config,
    recorder: &mut Recorder,
    signals: SignalHandlingMode,
    mut done: impl FnMut(&Recorder) -> bool,
) -> Result<()> {
    let iox = NodeBuilder::new()
        .config(iceoryx)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<ipc::Service>()
        .map_err(|e| anyhow!("recorder node: {e:?}"))?;
    let mut listeners = Vec::new();
    let mut listening = BTreeSet::new();
    let started = Instant::now();
    loop {
        recorder.discover()?;
        for topic in recorder
            .taps()
            .map(|t| t.topic().to_string())
            .collect::<Vec<_>>()
        {
            if listening.insert(topic.clone()) {
                listeners.push(caravan::tap::open_listener(&iox, &topic)?);
            }
        }
        let next_discovery = Instant::now() + discovery_interval(started);
        let ended = listen_until::<anyhow::Error, _>(
            &listeners.iter().collect::<Vec<_>>(),
            next_discovery,
            signals,
            || {
                recorder.drain()?;
                Ok(done(recorder))
            },
        )?;
        if ended {
            return Ok(());
        }
    }
}
