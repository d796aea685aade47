//! The step loop: runs a node's step function under the realtime or the lockstep clock.

use crate::lockstep::{Client, GrantOutcome};
use crate::stats::StepStats;
use crate::transport::Shared;
use crate::{Error, Publisher, Trigger};
use caravan_schemas::{FixedString, NodeStatus};
use iceoryx2::prelude::*;
use iceoryx2::waitset::WaitSetRunResult;
use std::rc::Rc;
use std::time::{Duration, Instant};

const STATUS_PERIOD_NS: u64 = 1_000_000_000;

/// What a step function sees of the current step.
pub struct Step {
    now_ns: u64,
    index: u64,
    stop: bool,
    /// The next step asked for with [`Step::wake_at`] ([`Trigger::Scheduled`] nodes).
    wake_ns: Option<u64>,
}

impl Step {
    /// Simulated time of this step since the group started.
    pub fn now(&self) -> Duration {
        Duration::from_nanos(self.now_ns)
    }

    pub fn now_ns(&self) -> u64 {
        self.now_ns
    }

    /// 0 for the first step.
    pub fn index(&self) -> u64 {
        self.index
    }

    /// Ends the run after this step.
    pub fn stop(&mut self) {
        self.stop = true;
    }

    /// Asks for the next step at simulated time `at` (a [`Trigger::Scheduled`] node; other
    /// triggers ignore it). A time not after this step's, or none asked for, leaves the node
    /// asleep until the run ends.
    pub fn wake_at(&mut self, at: Duration) {
        self.wake_ns = Some(at.as_nanos().min(u64::MAX as u128) as u64);
    }

    fn new() -> Self {
        Step {
            now_ns: 0,
            index: 0,
            stop: false,
            wake_ns: None,
        }
    }
}

/// Everything the loops need besides the clock.
pub(crate) struct Executor<'a> {
    pub shared: Rc<Shared>,
    pub name: &'a str,
    pub host: &'a str,
    pub status: &'a Publisher<NodeStatus>,
    pub epoch: Instant,
    pub epoch_offset_ns: u64,
    /// How long to look for the next message or grant before sleeping ([`crate::spin`]).
    pub spin: Duration,
}

fn interrupted(result: WaitSetRunResult) -> bool {
    matches!(
        result,
        WaitSetRunResult::TerminationRequest | WaitSetRunResult::Interrupt
    )
}

fn waitset() -> Result<WaitSet<ipc::Service>, Error> {
    WaitSetBuilder::new()
        .signal_handling_mode(SignalHandlingMode::HandleTerminationRequests)
        .create::<ipc::Service>()
        .map_err(|e| Error::transport("waitset", e))
}

impl Executor<'_> {
    fn publish_status(&self, stats: &StepStats, running: bool) -> Result<(), Error> {
        self.status.publish(&NodeStatus {
            node: FixedString::new(self.name),
            host: FixedString::new(self.host),
            messages_missed: self.shared.missed.get(),
            sim_time_ns: self.shared.now_ns.get(),
            running: running as u32,
            rss_kib: crate::stats::resident_kib(),
            ..stats.summary()
        })
    }

    /// Runs `step` once at simulated time `now_ns`, timing it.
    fn run_step<F>(
        &self,
        step: &mut F,
        stats: &mut StepStats,
        state: &mut Step,
        due_ns: u64,
        start_ns: u64,
    ) -> Result<(), Error>
    where
        F: FnMut(&mut Step) -> Result<(), Error>,
    {
        let stamped_by_cpu = self.shared.stamping_slowdown().is_some();
        let cpu_started = (stats.cpu_due() || stamped_by_cpu).then(crate::stats::thread_cpu_ns);
        let started = Instant::now();
        self.shared.in_step.set(true);
        self.shared.step_cpu_started_ns.set(cpu_started);
        let arrivals = &self.shared.arrivals;
        arrivals.set(arrivals.get() + 1);
        // Subscribers note what they still hold while the step reads them.
        self.shared.next_arrival_ns.set(u64::MAX);
        let stepped = step(state);
        // Outside a step (a final status, a message published between steps) nothing is
        // computing: its messages carry the step's time.
        self.shared.in_step.set(false);
        self.shared.step_cpu_started_ns.set(None);
        stepped?;
        let compute = crate::StepCompute {
            wall_ns: started.elapsed().as_nanos() as u64,
            cpu_ns: cpu_started.map(|c| crate::stats::thread_cpu_ns().saturating_sub(c)),
        };
        stats.record(start_ns, due_ns, compute);
        state.index += 1;
        Ok(())
    }

    fn since_epoch_ns(&self) -> u64 {
        self.epoch_offset_ns + self.epoch.elapsed().as_nanos() as u64
    }

    /// Wall-clock execution: the WaitSet sleeps until the period elapses or a message arrives.
    pub fn run_realtime<F>(&self, trigger: &Trigger, mut step: F) -> Result<NodeStatus, Error>
    where
        F: FnMut(&mut Step) -> Result<(), Error>,
    {
        let listener = match trigger {
            Trigger::OnMessage(topic) => Some(self.shared.listener(topic)?),
            Trigger::Every(_) | Trigger::Scheduled => None,
        };
        // A scheduled node steps at once, then when it asks (ns since the group's epoch).
        let scheduled = matches!(trigger, Trigger::Scheduled);
        let mut wake_ns = scheduled.then_some(0u64);
        let ws = waitset()?;
        let mut stats = StepStats::new(trigger.period());
        let mut state = Step::new();
        let attach_err = |e| Error::transport("waitset attach", e);
        let period_guard = trigger
            .period()
            .map(|p| ws.attach_interval(p))
            .transpose()
            .map_err(attach_err)?;
        let message_guard = listener
            .as_ref()
            .map(|l| ws.attach_notification(l.as_ref()))
            .transpose()
            .map_err(attach_err)?;
        let status_guard = ws
            .attach_interval(Duration::from_nanos(STATUS_PERIOD_NS))
            .map_err(|e| Error::transport("waitset attach", e))?;
        let period_ns = trigger.period().map_or(0, |p| p.as_nanos() as u64);
        let mut next_due_ns = self.since_epoch_ns() + period_ns;
        // Spinning pays after a step (an answer may come at once), not after a status wake-up.
        let mut stepped = false;
        let outcome = loop {
            let (mut fired, mut status_due) = (false, false);
            let on_event = |id: WaitSetAttachmentId<ipc::Service>| {
                fired |= period_guard.as_ref().is_some_and(|g| id.has_event_from(g))
                    || message_guard.as_ref().is_some_and(|g| id.has_event_from(g));
                status_due |= id.has_event_from(&status_guard);
                CallbackProgression::Continue
            };
            // A node stepped by messages also wakes when a message delayed by a link arrives.
            let arrival = self.shared.next_arrival_ns.get();
            // Spin, then park: a notification found while spinning (a non-blocking read of the
            // listener's socket; the loop knows the topic's event, not its subscriber) saves
            // the wake-up.
            let spun = match &listener {
                Some(l) if stepped && !self.spin.is_zero() && arrival == u64::MAX => {
                    crate::spin::spin_for(self.spin, || {
                        let notified = l.try_wait(|_| {});
                        notified
                            .map(|n| (n > 0).then_some(()))
                            .map_err(|e| Error::transport("listener", e))
                    })?
                    .is_some()
                }
                _ => false,
            };
            let result = if spun {
                // Only to see to the status interval and signals; the step is due already.
                ws.wait_and_process_once_with_timeout(on_event, Duration::ZERO)
                    .map_err(|e| Error::transport("waitset wait", e))?
            } else if listener.is_some() && arrival != u64::MAX {
                let timeout = Duration::from_nanos(arrival.saturating_sub(crate::wall_clock_ns()));
                let result = ws
                    .wait_and_process_once_with_timeout(on_event, timeout)
                    .map_err(|e| Error::transport("waitset wait", e))?;
                fired |= crate::wall_clock_ns() >= arrival;
                result
            } else if let Some(wake) = wake_ns {
                let timeout = Duration::from_nanos(wake.saturating_sub(self.since_epoch_ns()));
                let result = ws
                    .wait_and_process_once_with_timeout(on_event, timeout)
                    .map_err(|e| Error::transport("waitset wait", e))?;
                if self.since_epoch_ns() >= wake {
                    fired = true;
                    wake_ns = None;
                }
                result
            } else {
                ws.wait_and_process_once(on_event)
                    .map_err(|e| Error::transport("waitset wait", e))?
            };
            fired |= spun;
            if interrupted(result) {
                break Ok(());
            }
            // Draining counts as hearing: a notification that came after the wait returned for
            // another reason (the status interval) would otherwise be consumed unheard, and the
            // message it announced would wait for the next one, which may never come.
            if let Some(listener) = &listener {
                let drained = listener
                    .try_wait(|_| {})
                    .map_err(|e| Error::transport("listener", e))?;
                fired |= drained > 0;
            }
            stepped = fired;
            if fired {
                let start_ns = self.since_epoch_ns();
                let due_ns = if period_ns > 0 { next_due_ns } else { start_ns };
                state.now_ns = start_ns;
                self.shared.now_ns.set(start_ns);
                if let Err(e) = self.run_step(&mut step, &mut stats, &mut state, due_ns, start_ns) {
                    break Err(e);
                }
                // After a long stall, resume the period from now instead of bursting.
                next_due_ns = (next_due_ns + period_ns).max(start_ns);
                if scheduled {
                    wake_ns = state.wake_ns.take().filter(|&w| w > start_ns);
                }
            }
            if status_due {
                self.publish_status(&stats, true)?;
            }
            if state.stop {
                break Ok(());
            }
        };
        self.publish_status(&stats, false)?;
        outcome.map(|_| stats.summary())
    }

    /// Lockstep execution: step exactly at the simulated times the scheduler grants.
    pub fn run_lockstep<F>(&self, trigger: &Trigger, mut step: F) -> Result<NodeStatus, Error>
    where
        F: FnMut(&mut Step) -> Result<(), Error>,
    {
        let ws = waitset()?;
        let triggers: Vec<&str> = match trigger {
            Trigger::OnMessage(topic) => vec![topic.as_str()],
            Trigger::Every(_) | Trigger::Scheduled => vec![],
        };
        let client = Client::connect(self.shared.clone(), self.name, trigger.period(), &triggers)?;
        let _grants = ws
            .attach_notification(client.grant_listener())
            .map_err(|e| Error::transport("lockstep grant wait", e))?;
        let mut stats = StepStats::new(trigger.period());
        let mut state = Step::new();
        let mut next_status_ns = 0;
        let period_ns = trigger.period().map_or(0, |p| p.as_nanos() as u64);
        let outcome = 'run: loop {
            let grant = match client.wait_for_grant(&ws, self.spin)? {
                GrantOutcome::Step(grant) => grant,
                GrantOutcome::Stop | GrantOutcome::Terminated => break Ok(()),
            };
            self.shared.tick_ns.set(grant.tick_ns);
            // A grant of several periods: every step as if granted alone, one report.
            let mut now_ns = grant.now_ns;
            let mut index = 0;
            loop {
                self.shared.now_ns.set(now_ns);
                self.shared.step_of_grant.set(index);
                state.now_ns = now_ns;
                if let Err(e) = self.run_step(&mut step, &mut stats, &mut state, now_ns, now_ns) {
                    break 'run Err(e);
                }
                if now_ns >= next_status_ns {
                    self.publish_status(&stats, true)?;
                    next_status_ns = now_ns + STATUS_PERIOD_NS;
                }
                // A step that sent a topic two messages ends the grant here: its readers hold
                // one message per step ahead of them (`Shared::burst`).
                let burst = self.shared.burst.get();
                // The next step: a period on, or for a node stepped by messages when the
                // next one it holds shows.
                let next_ns = match trigger {
                    _ if period_ns > 0 => now_ns + period_ns,
                    Trigger::OnMessage(_) => self.shared.next_arrival_ns.get(),
                    _ => u64::MAX,
                };
                if state.stop || burst || next_ns <= now_ns || next_ns > grant.last_ns() {
                    break;
                }
                index += 1;
                now_ns = next_ns;
            }
            // A node stepped by messages asks to step again when a held message arrives.
            let arrival = self.shared.next_arrival_ns.get();
            let wake_ns = match trigger {
                Trigger::OnMessage(_) if arrival != u64::MAX => arrival,
                Trigger::Scheduled => state.wake_ns.take().unwrap_or(0),
                _ => 0,
            };
            client.report_done(now_ns, wake_ns, grant.last_ns() > grant.now_ns)?;
            if state.stop {
                break Ok(());
            }
        };
        self.publish_status(&stats, false)?;
        outcome.map(|_| stats.summary())
    }
}
