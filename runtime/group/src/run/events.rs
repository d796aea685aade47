//! The launcher's main loop: react to process exits (restart policies, required processes),
//! signals, hung nodes, the end of the schedule and the realtime duration, until every
//! process of the group is gone.

use super::driver::Control;
use super::output::Console;
use super::supervisor::{Event, Supervisor};
use anyhow::Result;
use caravan_bridge::{Bridge, FleetEvent};
use caravan_launch::model::LaunchFile;
use crossbeam::channel::{Receiver, RecvTimeoutError};
use std::sync::atomic::Ordering;
use std::time::Instant;

/// How the run ended: "completed", "interrupted" or "failed", and why it failed.
pub struct Ending {
    pub outcome: &'static str,
    pub failure: Option<String>,
}

/// Supervises the started group until all its processes have exited. On several machines
/// (`fleet`), a host whose processes have all exited waits for the other hosts' to, and a stop
/// on one host stops every host.
pub fn supervise(
    lf: &LaunchFile,
    sup: &mut Supervisor,
    events: &Receiver<Event>,
    control: &Control,
    console: &Console,
    started: Instant,
    fleet: Option<&Bridge>,
) -> Result<Ending> {
    let lockstep = lf.group.clock == caravan::ClockMode::Lockstep;
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
    // Whether the other hosts know why this one stops (they stopped it, or all are done).
    let mut told = fleet.is_none();
    let mut said_done = false;
    loop {
        if let Some(fleet) = fleet {
            if stopping && !told {
                fleet.stop(outcome, failure.as_deref());
                told = true;
            }
            if !stopping && !said_done && sup.all_done() {
                fleet.local_done();
                said_done = true;
            }
        }
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
                let nodes = sup.nodes_of(index);
                control.deaths.lock().unwrap().extend(nodes.iter().cloned());
                let ending = lf
                    .processes
                    .iter()
                    .find(|p| nodes.contains(&p.name) && p.ends_group);
                let (ends, name) = (ending.is_some(), ending.map_or("", |p| &p.name));
                match sup.on_exit(index, generation, status, usage, &last_error, stopping) {
                    Ok(Some(at)) => next_restart = Some(next_restart.map_or(at, |n| n.min(at))),
                    Ok(None) => {}
                    Err(why) => {
                        console.say(&why);
                        (outcome, failure) = ("failed", Some(why));
                        begin_stop(sup, &mut stopping, &mut kill_at);
                    }
                }
                if ends && !stopping {
                    console.say(&format!("process '{name}' ended the group (ends_group)"));
                    if !status.success() {
                        (outcome, failure) = ("failed", Some(format!("process '{name}' failed")));
                    }
                    begin_stop(sup, &mut stopping, &mut kill_at);
                }
                // On several machines the group ends when every host's processes have.
                if !stopping && sup.all_done() && fleet.is_none() {
                    begin_stop(sup, &mut stopping, &mut kill_at);
                }
            }
            Ok(Event::Signal(sig)) => {
                if stopping {
                    // A second Ctrl-C: do not wait for the grace period.
                    sup.signal_all(libc::SIGKILL);
                } else {
                    console.say(&format!("stopping the group (signal {sig})"));
                    outcome = "interrupted";
                    begin_stop(sup, &mut stopping, &mut kill_at);
                }
            }
            Ok(Event::Hung {
                names,
                now_ns,
                timeout,
            }) => {
                for name in names {
                    let at = format!(
                        "process '{name}' has not finished a step at {:.3} s for {timeout:?} (step_timeout)",
                        now_ns as f64 * 1e-9
                    );
                    // Across hosts, a process left out here runs on another host.
                    let remote = fleet.and(lf.left_out.get(&name));
                    if let Some(host) = remote {
                        if stopping {
                            continue;
                        }
                        // Its launcher kills it when the group stops.
                        let why = format!("{at} on host '{host}'");
                        console.say(&why);
                        (outcome, failure) = ("failed", Some(why));
                        begin_stop(sup, &mut stopping, &mut kill_at);
                    } else {
                        console.say(&format!("{at}; it looks hung, killing it"));
                        sup.kill(&name);
                    }
                }
            }
            Ok(Event::Silent { names, timeout }) => {
                let running: Vec<String> =
                    names.into_iter().filter(|n| sup.is_running(n)).collect();
                for name in running {
                    console.say(&format!(
                        "process '{name}' has not reported a status in {timeout:?} since the start (join_timeout); killing it"
                    ));
                    sup.kill(&name);
                }
            }
            Ok(Event::DriverDone(result)) => {
                if let Err(why) = result {
                    console.say(&why);
                    (outcome, failure) = ("failed", Some(why));
                }
                begin_stop(sup, &mut stopping, &mut kill_at);
            }
            Ok(Event::Fleet(event)) => {
                if stopping {
                    continue;
                }
                match event {
                    FleetEvent::Stopped(notice) => {
                        told = true;
                        let why = notice.failure.as_deref().unwrap_or("");
                        console.say(&format!(
                            "host '{}' stopped the group ({}{}{why})",
                            notice.host,
                            notice.outcome,
                            if why.is_empty() { "" } else { ": " }
                        ));
                        outcome = match notice.outcome.as_str() {
                            "failed" => "failed",
                            "interrupted" => "interrupted",
                            _ => "completed",
                        };
                        failure = notice
                            .failure
                            .map(|f| format!("host '{}': {f}", notice.host));
                    }
                    FleetEvent::Left { host, required } => {
                        if !required {
                            console.say(&format!(
                                "host '{host}' left the group; going on without it (required = false)"
                            ));
                            continue;
                        }
                        let why =
                            format!("host '{host}' left the group before its processes finished");
                        console.say(&why);
                        (outcome, failure) = ("failed", Some(why));
                    }
                    FleetEvent::AllDone => told = true,
                    FleetEvent::Failed(why) => {
                        console.say(&why);
                        (outcome, failure) = ("failed", Some(why));
                    }
                }
                begin_stop(sup, &mut stopping, &mut kill_at);
            }
            Err(RecvTimeoutError::Timeout) => {
                let now = Instant::now();
                if kill_at.is_some_and(|k| k <= now) {
                    console.say("grace period over; killing the remaining processes");
                    sup.signal_all(libc::SIGKILL);
                    kill_at = None;
                }
                if wall_deadline.is_some_and(|d| d <= now) && !stopping {
                    begin_stop(sup, &mut stopping, &mut kill_at);
                }
                if next_restart.is_some_and(|r| r <= now) && !stopping {
                    next_restart = sup.restart_due(now)?;
                }
            }
            Err(RecvTimeoutError::Disconnected) => break,
        }
    }
    Ok(Ending { outcome, failure })
}
