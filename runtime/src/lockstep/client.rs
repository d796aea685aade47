//! The node side of the protocol.

use super::control::{
    Pub, Sub, has_samples, listener, notifier, publisher, send, spin_on, subscriber,
};
use crate::Error;
use crate::transport::Shared;
use caravan_schemas::lockstep::{self as proto, Done, Grant, Hello};
use caravan_schemas::{FixedString, FixedVec};
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::prelude::*;
use iceoryx2::waitset::WaitSetRunResult;
use iceoryx2_bb_posix::file_descriptor::FileDescriptorBased;
use std::rc::Rc;
use std::time::Duration;

/// What a node waiting for a grant learns.
pub enum GrantOutcome {
    Step(Grant),
    Stop,
    /// SIGTERM or SIGINT arrived while waiting.
    Terminated,
}

/// The node side of the protocol.
pub struct Client {
    node_hash: u64,
    grants: Sub<Grant>,
    grant_listener: Listener<ipc::Service>,
    /// Made when first needed by a node holding the page of quiet steps (it reports into its
    /// slot), at once by any other: a publisher connected to the report service costs the
    /// scheduler a look at each receive.
    done: std::cell::OnceCell<Pub<Done>>,
    done_notifier: Notifier<ipc::Service>,
    /// Kept open: a sample whose publisher is gone before the subscriber attached is lost.
    _hello: Pub<Hello>,
    hello_notifier: Notifier<ipc::Service>,
    hello: Hello,
    /// The last report, repeated if the scheduler grants the same step again.
    last_done: std::cell::RefCell<Option<Done>>,
    /// This machine's count of quiet steps, if the group's scheduler made one here.
    pending: Option<super::pending::Pending>,
    /// The step being taken was granted quiet.
    quiet_step: std::cell::Cell<bool>,
    /// Its report slot in `pending` (`slots.rs`), looked for at its first quiet report.
    slot: std::cell::OnceCell<Option<usize>>,
    /// The last report went into the slot (a repeat of it need not be written again).
    last_in_slot: std::cell::Cell<bool>,
    /// The sequence of the last grant read from the slot (`slots.rs`).
    grant_seen: std::cell::Cell<u64>,
    shared: Rc<Shared>,
}

impl Client {
    pub fn connect(
        shared: Rc<Shared>,
        node: &str,
        period: Option<Duration>,
        triggers: &[&str],
    ) -> Result<Self, Error> {
        let iox = &shared.iox;
        let grant_name = proto::grant_service(node);
        let mut hello = Hello {
            node: FixedString::new(node),
            container: crate::container::id(),
            period_ns: period.map_or(0, |p| p.as_nanos() as u64),
            triggers: FixedVec::new(),
            inputs: FixedVec::new(),
            outputs: FixedVec::new(),
            declared: 0,
            quiet: 0,
            output_depth: 0,
            _reserved: 0,
        };
        let pending = super::pending::Pending::open(iox.config());
        hello.quiet = pending.as_ref().map_or(0, |p| p.token());
        for topic in triggers {
            hello.triggers.push(proto::name_hash(topic)).map_err(|_| {
                Error::Lockstep(format!("node '{node}' triggers on too many topics"))
            })?;
        }
        {
            let mut ports = shared.ports.borrow_mut();
            ports.joined = true;
            // A self-scheduled node asks for times between ticks.
            let mut declared = !ports.undeclared && (period.is_some() || !triggers.is_empty());
            for (list, out) in [
                (&ports.inputs, &mut hello.inputs),
                (&ports.outputs, &mut hello.outputs),
            ] {
                for &topic in list {
                    declared &= out.push(topic).is_ok();
                }
            }
            hello.declared = declared as u32;
            // Publishing to nothing, nothing bounds how many steps it may take at once.
            hello.output_depth = match ports.outputs.is_empty() {
                true => u32::MAX,
                false => ports.output_depth.min(u32::MAX as usize) as u32,
            };
        }
        let client = Self {
            node_hash: shared.node_hash,
            grants: subscriber::<Grant>(iox, &grant_name)?,
            grant_listener: listener(iox, &grant_name)?,
            done: std::cell::OnceCell::new(),
            done_notifier: notifier(iox, proto::DONE)?,
            _hello: publisher::<Hello>(iox, proto::HELLO)?,
            hello_notifier: notifier(iox, proto::HELLO)?,
            hello,
            last_done: std::cell::RefCell::new(None),
            pending,
            quiet_step: std::cell::Cell::new(false),
            slot: std::cell::OnceCell::new(),
            last_in_slot: std::cell::Cell::new(false),
            grant_seen: std::cell::Cell::new(0),
            shared: shared.clone(),
        };
        if client.pending.is_none() {
            client.done_port()?;
        }
        client.say_hello()?;
        Ok(client)
    }

    /// Blocks (event-driven) until the scheduler grants a new step or stops the run.
    ///
    /// iceoryx2 can, rarely, fail to connect a new publisher to a subscriber, losing a
    /// sample; the protocol therefore tolerates repeats: until the first grant the hello is
    /// sent again every second, and a repeated grant for the step already done is answered by
    /// repeating its report (the scheduler re-grants when a report is overdue).
    ///
    /// `waitset` must have [`Self::grant_listener`] attached (once: attaching costs system
    /// calls, and every step waits here).
    pub fn wait_for_grant(
        &self,
        waitset: &WaitSet<ipc::Service>,
        spin: Duration,
    ) -> Result<GrantOutcome, Error> {
        loop {
            while let Some(grant) = self.next_grant()? {
                if grant.stop != 0 {
                    return Ok(GrantOutcome::Stop);
                }
                match *self.last_done.borrow() {
                    // A repeat is never quiet: it was not counted.
                    // The grant of the last report, which may have ended its steps early.
                    Some(done) if (grant.now_ns..=grant.last_ns()).contains(&done.now_ns) => {
                        if !self.last_in_slot.get() {
                            send(self.done_port()?, done, proto::DONE)?;
                        }
                        self.notify_done(true)?
                    }
                    Some(done) if grant.last_ns() < done.now_ns => {}
                    _ => {
                        self.quiet_step.set(
                            grant.quiet != 0
                                && self
                                    .pending
                                    .as_ref()
                                    .is_some_and(|p| p.token() == grant.quiet),
                        );
                        return Ok(GrantOutcome::Step(grant));
                    }
                }
            }
            // Waits up to `timeout` for a grant: whether SIGTERM or SIGINT came, and whether the
            // wait ended for this node (its event, or the time), not for another member of its
            // container, whose wake-up may have brought this node's grant too.
            let wait = |timeout| -> Result<(bool, bool), Error> {
                // In a container the thread goes to the other members meanwhile.
                // SAFETY: the descriptor is only polled, while the listener lives.
                let fd = unsafe { self.grant_listener.file_descriptor().native_handle() };
                if let Some(unparked) = crate::container::park(fd, timeout) {
                    return Ok((unparked.terminated, !unparked.peeked));
                }
                let result = waitset
                    .wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, timeout)
                    .map_err(|e| Error::transport("lockstep grant wait", e))?;
                Ok((
                    matches!(
                        result,
                        WaitSetRunResult::TerminationRequest | WaitSetRunResult::Interrupt
                    ),
                    true,
                ))
            };
            if spin_on(|| self.grant_in(), &self.grant_listener, spin, "grant")? {
                // A node that keeps finding grants never sleeps in its WaitSet, which is where
                // a signal is noticed: look without waiting.
                if wait(Duration::ZERO)?.0 {
                    return Ok(GrantOutcome::Terminated);
                }
                continue;
            }
            let (stop, own) = wait(Duration::from_secs(1))?;
            if own {
                self.grant_listener
                    .try_wait(|_| {})
                    .map_err(|e| Error::transport("grant", e))?;
            }
            if stop {
                return Ok(GrantOutcome::Terminated);
            }
            if own && self.last_done.borrow().is_none() {
                self.say_hello()?;
            }
        }
    }

    /// The next grant: from the slot, once the scheduler writes them there (`slots.rs`), else
    /// a `Grant` sample.
    fn next_grant(&self) -> Result<Option<Grant>, Error> {
        if let (Some(pending), Some(&Some(slot))) = (&self.pending, self.slot.get())
            && let Some((seq, grant)) = pending.read_grant(slot, self.grant_seen.get())
        {
            self.grant_seen.set(seq);
            return Ok(Some(grant));
        }
        let sample = (self.grants.receive()).map_err(|e| Error::transport("grant", e))?;
        Ok(sample.map(|s| *s.payload()))
    }

    /// Whether a grant is in, without taking it.
    fn grant_in(&self) -> Result<bool, Error> {
        if let (Some(pending), Some(&Some(slot))) = (&self.pending, self.slot.get())
            && pending.grant_sequence(slot) != self.grant_seen.get()
        {
            return Ok(true);
        }
        has_samples(&self.grants, "grant")
    }

    /// The listener a grant wakes.
    pub fn grant_listener(&self) -> &Listener<ipc::Service> {
        &self.grant_listener
    }

    fn say_hello(&self) -> Result<(), Error> {
        send(&self._hello, self.hello, proto::HELLO)?;
        self.hello_notifier
            .notify()
            .map_err(|e| Error::transport(proto::HELLO, e))?;
        Ok(())
    }

    /// Reports the step at `now_ns` finished, with the topics it published to: the last of
    /// its grant's steps, which were several if `several` (`Grant::until_ns`), each topic
    /// then with the steps that published there ([`Done::STEPS`]). `wake_ns` (0 for none) asks
    /// for another step when a held message becomes visible.
    pub fn report_done(&self, now_ns: u64, wake_ns: u64, several: bool) -> Result<(), Error> {
        let mut done = Done {
            node_hash: self.node_hash,
            now_ns,
            wake_ns,
            published: FixedVec::new(),
            undeclared: self.shared.ports.borrow().undeclared as u32,
            flags: if self.shared.burst.replace(false) {
                Done::BURST
            } else {
                0
            },
        };
        let mut published = self.shared.published.borrow_mut();
        let steps = several && published.len() * 2 <= proto::MAX_TOPICS;
        if steps {
            done.flags |= Done::STEPS;
        }
        for (topic, bits) in published.drain(..) {
            // More topics than fit cannot be scheduled precisely; the node is still woken by
            // its period, so truncation only delays subscribers. The scheduler no longer
            // knows what it published: it is not overlapped from then on.
            let pushed = match steps {
                true => done
                    .published
                    .push(topic)
                    .and_then(|()| done.published.push(bits as u64)),
                false => done.published.push(topic),
            };
            if pushed.is_err() {
                self.shared.ports.borrow_mut().undeclared = true;
                done.undeclared = 1;
            }
        }
        drop(published);
        *self.last_done.borrow_mut() = Some(done);
        let quiet = self.quiet_step.replace(false);
        let slot = match &self.pending {
            Some(pending) if quiet => {
                let slot = self.slot.get_or_init(|| {
                    let slot = pending.find_slot(self.node_hash);
                    // Grants come into the slot only after this report.
                    if let Some(slot) = slot {
                        self.grant_seen.set(pending.grant_sequence(slot));
                    }
                    slot
                });
                slot.map(|slot| (pending, slot))
            }
            _ => None,
        };
        self.last_in_slot.set(slot.is_some());
        match slot {
            Some((pending, slot)) => pending.write_report(
                slot,
                &super::Report {
                    now_ns,
                    wake_ns,
                    undeclared: done.undeclared,
                    flags: done.flags,
                    published: done.published.as_slice(),
                },
            ),
            None => send(self.done_port()?, done, proto::DONE)?,
        }
        // Taken off the count after the report is out: the last quiet step to end then comes
        // after every report, so none waits unread for the scheduler's poll. (The scheduler may
        // read this report and set the count to 0 before it is taken off: the count goes to
        // −1, which only means more notifications until the next reset.)
        let notify = match (&self.pending, quiet) {
            (Some(pending), true) => pending.finish(),
            _ => true,
        };
        self.notify_done(notify)
    }

    /// The report service's publisher, made at its first use.
    fn done_port(&self) -> Result<&Pub<Done>, Error> {
        if let Some(port) = self.done.get() {
            return Ok(port);
        }
        let port = publisher::<Done>(&self.shared.iox, proto::DONE)?;
        Ok(self.done.get_or_init(|| port))
    }

    /// Wakes the scheduler for a report sent, if `notify` (else it reads the report when a
    /// later one, or the last quiet step, wakes it: see `pending.rs`).
    fn notify_done(&self, notify: bool) -> Result<(), Error> {
        if notify {
            self.done_notifier
                .notify()
                .map_err(|e| Error::transport(proto::DONE, e))?;
        }
        Ok(())
    }
}
