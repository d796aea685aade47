//! The lockstep protocol: simulated time granted step by step.
//!
//! Each node announces itself ([`Hello`]: its period, the topics that wake it), then repeats:
//! wait for a [`Grant`] of simulated time t, step at t, report [`Done`] with the topics it
//! published. The [`Scheduler`] owns time: at each event time it grants every due node at once,
//! waits until all reported done, and only then advances. A message published at t wakes its
//! triggered subscribers at t + tick and is invisible to them before, so runs are deterministic
//! whatever the machine's load.

use crate::Error;
use crate::transport::{self, Shared};
use caravan_schemas::lockstep::{self as proto, Done, Grant, Hello};
use caravan_schemas::{FixedString, FixedVec, Header};
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::prelude::*;
use std::collections::{BTreeMap, BTreeSet};
use std::rc::Rc;
use std::time::Duration;

type Pub<T> = iceoryx2::port::publisher::Publisher<ipc::Service, T, Header>;
type Sub<T> = iceoryx2::port::subscriber::Subscriber<ipc::Service, T, Header>;

fn control_topic<T: caravan_schemas::Message>(
    iox: &iceoryx2::node::Node<ipc::Service>,
    name: &str,
) -> Result<
    iceoryx2::service::port_factory::publish_subscribe::PortFactory<ipc::Service, T, Header>,
    Error,
> {
    // Control messages must never be lost; queues are deep enough that nobody waits in practice.
    transport::open_pubsub::<T>(iox, name, crate::Delivery::Lossless { depth: 256 })
}

fn publisher<T: caravan_schemas::Message>(
    iox: &iceoryx2::node::Node<ipc::Service>,
    name: &str,
) -> Result<Pub<T>, Error> {
    control_topic::<T>(iox, name)?
        .publisher_builder()
        .backpressure_strategy(BackpressureStrategy::RetryUntilDelivered)
        .create()
        .map_err(|e| Error::transport(name, e))
}

fn subscriber<T: caravan_schemas::Message>(
    iox: &iceoryx2::node::Node<ipc::Service>,
    name: &str,
) -> Result<Sub<T>, Error> {
    control_topic::<T>(iox, name)?
        .subscriber_builder()
        .buffer_size(256)
        .create()
        .map_err(|e| Error::transport(name, e))
}

fn send<T: caravan_schemas::Message>(port: &Pub<T>, value: T, name: &str) -> Result<(), Error> {
    let sample = port.loan_uninit().map_err(|e| Error::transport(name, e))?;
    sample
        .write_payload(value)
        .send()
        .map_err(|e| Error::transport(name, e))?;
    Ok(())
}

/// What a node waiting for a grant learns.
pub(crate) enum GrantOutcome {
    Step(Grant),
    Stop,
    /// SIGTERM or SIGINT arrived while waiting.
    Terminated,
}

/// The node side of the protocol.
pub(crate) struct Client {
    node_hash: u64,
    grants: Sub<Grant>,
    grant_listener: Listener<ipc::Service>,
    done: Pub<Done>,
    done_notifier: Notifier<ipc::Service>,
    /// Kept open: a sample whose publisher is gone before the subscriber attached is lost.
    _hello: Pub<Hello>,
    hello_notifier: Notifier<ipc::Service>,
    hello: Hello,
    /// The last report, repeated if the scheduler grants the same step again.
    last_done: std::cell::RefCell<Option<Done>>,
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
            period_ns: period.map_or(0, |p| p.as_nanos() as u64),
            triggers: FixedVec::new(),
        };
        for topic in triggers {
            hello.triggers.push(proto::name_hash(topic)).map_err(|_| {
                Error::Lockstep(format!("node '{node}' triggers on too many topics"))
            })?;
        }
        let client = Self {
            node_hash: shared.node_hash,
            grants: subscriber::<Grant>(iox, &grant_name)?,
            grant_listener: transport::listener(iox, &grant_name)?,
            done: publisher::<Done>(iox, proto::DONE)?,
            done_notifier: transport::notifier(iox, proto::DONE)?,
            _hello: publisher::<Hello>(iox, proto::HELLO)?,
            hello_notifier: transport::notifier(iox, proto::HELLO)?,
            hello,
            last_done: std::cell::RefCell::new(None),
            shared: shared.clone(),
        };
        client.say_hello()?;
        Ok(client)
    }

    /// Blocks (event-driven) until the scheduler grants a new step or stops the run.
    ///
    /// iceoryx2 can, rarely, fail to connect a new publisher to a subscriber, losing a
    /// sample; the protocol therefore tolerates repeats: until the first grant the hello is
    /// sent again every second, and a repeated grant for the step already done is answered by
    /// repeating its report (the scheduler re-grants when a report is overdue).
    pub fn wait_for_grant(&self, waitset: &WaitSet<ipc::Service>) -> Result<GrantOutcome, Error> {
        let _guard = waitset
            .attach_notification(&self.grant_listener)
            .map_err(|e| Error::transport("lockstep grant wait", e))?;
        loop {
            while let Some(sample) = self
                .grants
                .receive()
                .map_err(|e| Error::transport("grant", e))?
            {
                let grant = *sample.payload();
                if grant.stop != 0 {
                    return Ok(GrantOutcome::Stop);
                }
                match *self.last_done.borrow() {
                    Some(done) if grant.now_ns == done.now_ns => self.send_done(done)?,
                    Some(done) if grant.now_ns < done.now_ns => {}
                    _ => return Ok(GrantOutcome::Step(grant)),
                }
            }
            let result = waitset
                .wait_and_process_once_with_timeout(
                    |_| CallbackProgression::Continue,
                    Duration::from_secs(1),
                )
                .map_err(|e| Error::transport("lockstep grant wait", e))?;
            self.grant_listener
                .try_wait(|_| {})
                .map_err(|e| Error::transport("grant", e))?;
            if matches!(
                result,
                WaitSetRunResult::TerminationRequest | WaitSetRunResult::Interrupt
            ) {
                return Ok(GrantOutcome::Terminated);
            }
            if self.last_done.borrow().is_none() {
                self.say_hello()?;
            }
        }
    }

    fn say_hello(&self) -> Result<(), Error> {
        send(&self._hello, self.hello, proto::HELLO)?;
        self.hello_notifier
            .notify()
            .map_err(|e| Error::transport(proto::HELLO, e))?;
        Ok(())
    }

    /// Reports the step at `now_ns` finished, with the topics it published to.
    /// `wake_ns` (0 for none) asks for another step when a held message becomes visible.
    pub fn report_done(&self, now_ns: u64, wake_ns: u64) -> Result<(), Error> {
        let mut done = Done {
            node_hash: self.node_hash,
            now_ns,
            wake_ns,
            published: FixedVec::new(),
        };
        for topic in self.shared.published.borrow_mut().drain(..) {
            // More topics than fit cannot be scheduled precisely; the node is still woken by
            // its period, so truncation only delays subscribers.
            let _ = done.published.push(topic);
        }
        *self.last_done.borrow_mut() = Some(done);
        self.send_done(done)
    }

    fn send_done(&self, done: Done) -> Result<(), Error> {
        send(&self.done, done, proto::DONE)?;
        self.done_notifier
            .notify()
            .map_err(|e| Error::transport(proto::DONE, e))?;
        Ok(())
    }
}

use iceoryx2::waitset::WaitSetRunResult;

/// How long a node may take to report a step before its grant is repeated.
const REGRANT_AFTER: Duration = Duration::from_secs(1);

struct Member {
    name: String,
    /// False after the process died, until it says hello again (a restart).
    active: bool,
    period_ns: u64,
    /// Whether it steps when it joins: it has a period, or (neither a period nor triggers)
    /// it is scheduled by its own wake-ups and steps once to ask for the first.
    steps_on_joining: bool,
    /// Wall time from its last grant to its report: the longest-running nodes are granted
    /// first, so the step that bounds the advance starts soonest.
    last_step: Duration,
    grant: Pub<Grant>,
    grant_notifier: Notifier<ipc::Service>,
}

/// One advance of simulated time.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Advance {
    pub now_ns: u64,
    /// Names of the nodes that stepped, sorted.
    pub stepped: Vec<String>,
    /// Hashes of the topics published in this step, sorted.
    pub published: Vec<u64>,
}

/// Consulted while the scheduler waits, with the names of the nodes it waits for: returns the
/// names of nodes whose process died since the last call, or `Err` to abort the run.
pub trait Watchdog: FnMut(&[&str]) -> Result<Vec<String>, String> {}
impl<F: FnMut(&[&str]) -> Result<Vec<String>, String>> Watchdog for F {}

/// Owns simulated time for a group. The launcher runs one; tests can run one directly.
pub struct Scheduler {
    iox: iceoryx2::node::Node<ipc::Service>,
    tick_ns: u64,
    hello: Sub<Hello>,
    hello_listener: Listener<ipc::Service>,
    done: Sub<Done>,
    done_listener: Listener<ipc::Service>,
    members: Vec<Member>,
    by_hash: BTreeMap<u64, usize>,
    /// topic hash → members it wakes
    subscribers: BTreeMap<u64, Vec<usize>>,
    /// event time → members due then
    queue: BTreeMap<u64, BTreeSet<usize>>,
    /// How long one wait may last before `watchdog` is consulted.
    poll: Duration,
    now_ns: u64,
}

impl Scheduler {
    /// A scheduler on the group of `config`, with minimum message delay `tick`.
    pub fn new(config: &iceoryx2::config::Config, tick: Duration) -> Result<Self, Error> {
        crate::log::init("caravan");
        let iox = NodeBuilder::new()
            .config(config)
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<ipc::Service>()
            .map_err(|e| Error::transport("scheduler node", e))?;
        Ok(Self {
            hello: subscriber::<Hello>(&iox, proto::HELLO)?,
            hello_listener: transport::listener(&iox, proto::HELLO)?,
            done: subscriber::<Done>(&iox, proto::DONE)?,
            done_listener: transport::listener(&iox, proto::DONE)?,
            tick_ns: tick.as_nanos().max(1) as u64,
            iox,
            members: Vec::new(),
            by_hash: BTreeMap::new(),
            subscribers: BTreeMap::new(),
            queue: BTreeMap::new(),
            poll: Duration::from_millis(100),
            now_ns: 0,
        })
    }

    pub fn tick_ns(&self) -> u64 {
        self.tick_ns
    }

    /// Waits until every node in `expected` said hello. `watchdog` runs between waits; an `Err`
    /// from it (a member died, a timeout) aborts the wait.
    pub fn wait_for_nodes(
        &mut self,
        expected: &[String],
        mut watchdog: impl Watchdog,
    ) -> Result<(), Error> {
        let mut expected: BTreeSet<&str> = expected.iter().map(String::as_str).collect();
        loop {
            self.admit_new()?;
            let joined: BTreeSet<&str> = self.members.iter().map(|m| m.name.as_str()).collect();
            if expected.is_subset(&joined) {
                return Ok(());
            }
            let missing: Vec<&str> = expected.difference(&joined).copied().collect();
            let dead = watchdog(&missing).map_err(|why| {
                Error::Lockstep(format!(
                    "waiting for {} to start: {why}",
                    missing.join(", ")
                ))
            })?;
            // A process that died before joining is the supervisor's business (restart,
            // or stop the group if it was required); a restarted one joins later.
            for name in &dead {
                expected.remove(name.as_str());
            }
            self.wait_on(true)?;
        }
    }

    fn admit_new(&mut self) -> Result<(), Error> {
        while let Some(sample) = self
            .hello
            .receive()
            .map_err(|e| Error::transport("hello", e))?
        {
            self.admit(sample.payload())?;
        }
        Ok(())
    }

    fn admit(&mut self, hello: &Hello) -> Result<(), Error> {
        let name = hello.node.as_str().to_string();
        let hash = proto::name_hash(&name);
        if let Some(&i) = self.by_hash.get(&hash) {
            // A restarted process rejoins at the next tick.
            let member = &mut self.members[i];
            if !member.active {
                member.active = true;
                if member.steps_on_joining {
                    self.queue
                        .entry(self.now_ns + self.tick_ns)
                        .or_default()
                        .insert(i);
                }
            }
            return Ok(());
        }
        let index = self.members.len();
        let grant_name = proto::grant_service(&name);
        self.members.push(Member {
            active: true,
            grant: publisher::<Grant>(&self.iox, &grant_name)?,
            grant_notifier: transport::notifier(&self.iox, &grant_name)?,
            period_ns: hello.period_ns,
            steps_on_joining: hello.period_ns > 0 || hello.triggers.as_slice().is_empty(),
            last_step: Duration::ZERO,
            name,
        });
        self.by_hash.insert(hash, index);
        for topic in hello.triggers.as_slice() {
            self.subscribers.entry(*topic).or_default().push(index);
        }
        if self.members[index].steps_on_joining {
            self.queue.entry(self.now_ns).or_default().insert(index);
        }
        Ok(())
    }

    /// Time of the next event, if any node is due at all.
    pub fn next_time_ns(&self) -> Option<u64> {
        self.queue.keys().next().copied()
    }

    /// Grants the next event time to every node due then and waits until all are done.
    /// Returns `None` when no node will ever be due again.
    pub fn advance(&mut self, mut watchdog: impl Watchdog) -> Result<Option<Advance>, Error> {
        let Some((now_ns, due)) = self.queue.pop_first() else {
            return Ok(None);
        };
        self.now_ns = now_ns;
        let due: BTreeSet<usize> = due
            .into_iter()
            .filter(|&i| self.members[i].active)
            .collect();
        // Which order nodes are granted in changes nothing they see (a message is visible one
        // tick after it was sent), only how soon the slowest one starts.
        let mut order: Vec<usize> = due.iter().copied().collect();
        order.sort_by_key(|&i| std::cmp::Reverse(self.members[i].last_step));
        let started = std::time::Instant::now();
        for &i in &order {
            self.grant(i, Grant::step(now_ns, self.tick_ns))?;
        }
        let mut waiting = due.clone();
        let mut published = BTreeSet::new();
        let mut granted_at = started;
        while !waiting.is_empty() {
            while let Some(sample) = self
                .done
                .receive()
                .map_err(|e| Error::transport("done", e))?
            {
                let done = sample.payload();
                let Some(&i) = self.by_hash.get(&done.node_hash) else {
                    continue;
                };
                if done.now_ns > now_ns {
                    return Err(Error::Lockstep(format!(
                        "node '{}' reported a step at {} ns, but time is {} ns",
                        self.members[i].name, done.now_ns, now_ns
                    )));
                }
                // Repeats of reports (answers to repeated grants) are expected; skip them.
                if done.now_ns < now_ns || !waiting.remove(&i) {
                    continue;
                }
                self.members[i].last_step = started.elapsed();
                published.extend(done.published.as_slice().iter().copied());
                self.schedule_after(i, now_ns, done.published.as_slice());
                if done.wake_ns > now_ns {
                    self.queue.entry(done.wake_ns).or_default().insert(i);
                }
            }
            if waiting.is_empty() {
                break;
            }
            let names: Vec<&str> = waiting
                .iter()
                .map(|&i| self.members[i].name.as_str())
                .collect();
            let dead = watchdog(&names).map_err(|why| {
                Error::Lockstep(format!(
                    "waiting for {} to finish step at {now_ns} ns: {why}",
                    names.join(", ")
                ))
            })?;
            self.mark_dead(&dead, &mut waiting);
            self.admit_new()?;
            if granted_at.elapsed() > REGRANT_AFTER {
                // A grant (or its report) may have been lost; nodes answer repeats safely.
                for &i in &waiting {
                    self.grant(i, Grant::step(now_ns, self.tick_ns))?;
                }
                granted_at = std::time::Instant::now();
            }
            self.wait_on(false)?;
        }
        let mut stepped: Vec<String> = due.iter().map(|&i| self.members[i].name.clone()).collect();
        stepped.sort();
        Ok(Some(Advance {
            now_ns,
            stepped,
            published: published.into_iter().collect(),
        }))
    }

    /// Stops waiting for nodes whose process died; they rejoin when they say hello again.
    fn mark_dead(&mut self, dead: &[String], waiting: &mut BTreeSet<usize>) {
        for name in dead {
            if let Some(&i) = self.by_hash.get(&proto::name_hash(name)) {
                self.members[i].active = false;
                waiting.remove(&i);
            }
        }
    }

    /// Between advances: notes deaths and restarts reported by the watchdog.
    pub fn poll_members(&mut self, mut watchdog: impl Watchdog) -> Result<(), Error> {
        let dead = watchdog(&[]).map_err(Error::Lockstep)?;
        self.mark_dead(&dead, &mut BTreeSet::new());
        self.admit_new()
    }

    fn schedule_after(&mut self, i: usize, now_ns: u64, published: &[u64]) {
        let period = self.members[i].period_ns;
        if period > 0 {
            self.queue.entry(now_ns + period).or_default().insert(i);
        }
        for topic in published {
            for &j in self
                .subscribers
                .get(topic)
                .map(Vec::as_slice)
                .unwrap_or(&[])
            {
                self.queue
                    .entry(now_ns + self.tick_ns)
                    .or_default()
                    .insert(j);
            }
        }
    }

    fn grant(&self, i: usize, grant: Grant) -> Result<(), Error> {
        let member = &self.members[i];
        send(&member.grant, grant, &member.name)?;
        member
            .grant_notifier
            .notify()
            .map_err(|e| Error::transport(&member.name, e))?;
        Ok(())
    }

    /// Tells every node the run is over.
    pub fn stop_all(&mut self) -> Result<(), Error> {
        for i in 0..self.members.len() {
            if self.members[i].active {
                self.grant(i, Grant::stop(self.now_ns, self.tick_ns))?;
            }
        }
        Ok(())
    }

    fn wait_on(&self, hello: bool) -> Result<(), Error> {
        let listener = if hello {
            &self.hello_listener
        } else {
            &self.done_listener
        };
        listener
            .timed_wait(|_| {}, self.poll)
            .map_err(|e| Error::transport("scheduler wait", e))?;
        Ok(())
    }
}
