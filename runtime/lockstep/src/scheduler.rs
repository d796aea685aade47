//! The scheduler: owns simulated time, grants steps and collects their reports.

use crate::advance::{Advance, ScheduleStats, Watchdog};
use crate::members::{Flight, Member};
use crate::overlap::{self, Footprint};
use caravan::Error;
use caravan::lockstep::Pending;
use caravan::lockstep::control::{Sub, listener, spin_on, subscriber, wait_events};
use caravan_schemas::lockstep::{self as proto, Done, Grant, Hello};
use iceoryx2::port::listener::Listener;
use iceoryx2::prelude::*;
use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::time::{Duration, Instant};

/// How long a node may take to report a step before its grant is repeated.
const REGRANT_AFTER: Duration = Duration::from_secs(1);

/// How often a wait for reports looks for hellos (a restarted node's): each look reads a
/// service with a slot for every node, several times per tick otherwise.
const HELLO_EVERY: Duration = Duration::from_millis(10);

/// Owns simulated time for a group. The launcher runs one; tests can run one directly.
pub struct Scheduler {
    pub(crate) iox: iceoryx2::node::Node<ipc::Service>,
    pub(crate) tick_ns: u64,
    pub(crate) hello: Sub<Hello>,
    pub(crate) hello_listener: Listener<ipc::Service>,
    pub(crate) done: Sub<Done>,
    pub(crate) done_listener: Listener<ipc::Service>,
    pub(crate) members: Vec<Member>,
    pub(crate) by_hash: BTreeMap<u64, usize>,
    /// topic hash → members it wakes
    pub(crate) subscribers: BTreeMap<u64, Vec<usize>>,
    /// event time → members due then, for times not being stepped yet
    pub(crate) queue: BTreeMap<u64, BTreeSet<usize>>,
    /// Times being stepped, oldest first: one, or two when the next overlaps.
    pub(crate) flights: VecDeque<Flight>,
    /// Latest time that may start before the one before it has finished; `None`: none.
    pub(crate) overlap_until: Option<u64>,
    /// Topics a node may publish to while an earlier time runs (see [`Self::know_topics`]).
    pub(crate) known_topics: BTreeSet<u64>,
    /// How long one wait may last before `watchdog` is consulted.
    pub(crate) poll: Duration,
    /// How long a wait for reports spins before it sleeps ([`caravan::spin`]).
    pub(crate) spin: Duration,
    pub(crate) now_ns: u64,
    /// The last time that finished.
    pub(crate) last_finished_ns: Option<u64>,
    pub(crate) stats: ScheduleStats,
    /// The count of quiet steps its members on this machine share (`pending.rs`); `None`
    /// if it could not be made (every report then notifies, as a node of another machine's).
    pub(crate) pending: Option<Pending>,
    /// When a wait for reports last looked for hellos.
    pub(crate) hello_looked: Instant,
    /// The topics of the report being read from a slot, kept between reports.
    pub(crate) topics: Vec<u64>,
    /// Grants of several periods run up to this time (`batch.rs`); `None`: one at a time.
    pub(crate) batch_end: Option<u64>,
    /// The most steps a node waited for was granted at once ([`Self::longest_grant`]).
    longest_grant: std::rc::Rc<std::cell::Cell<u64>>,
    /// Times not being stepped yet → nodes that step then within a grant of an earlier time.
    pub(crate) ahead: BTreeMap<u64, Vec<usize>>,
    /// Each node's room for a batch, looking at its inputs' publishers and not; 0 until
    /// worked out (`batch.rs`, `Self::forget_rooms`).
    pub(crate) rooms: std::cell::RefCell<Vec<[u64; 2]>>,
}

impl Scheduler {
    /// A scheduler on the group of `config`, with minimum message delay `tick`. It makes the
    /// group's count of quiet steps ([`Pending`]); a launcher makes it before its processes
    /// start, so that each finds it when it joins, and hands it over with [`Self::with_pending`].
    pub fn new(config: &iceoryx2::config::Config, tick: Duration) -> Result<Self, Error> {
        Self::with_pending(config, tick, Pending::create_or_warn(config))
    }

    /// A scheduler with the count of quiet steps `pending` made before (see [`Self::new`]).
    pub fn with_pending(
        config: &iceoryx2::config::Config,
        tick: Duration,
        pending: Option<Pending>,
    ) -> Result<Self, Error> {
        caravan::log::init("caravan");
        let iox = NodeBuilder::new()
            .config(config)
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<ipc::Service>()
            .map_err(|e| Error::transport("scheduler node", e))?;
        Ok(Self {
            hello: subscriber::<Hello>(&iox, proto::HELLO)?,
            hello_listener: listener(&iox, proto::HELLO)?,
            done: subscriber::<Done>(&iox, proto::DONE)?,
            done_listener: listener(&iox, proto::DONE)?,
            tick_ns: tick.as_nanos().max(1) as u64,
            iox,
            members: Vec::new(),
            by_hash: BTreeMap::new(),
            subscribers: BTreeMap::new(),
            queue: BTreeMap::new(),
            flights: VecDeque::new(),
            overlap_until: None,
            known_topics: BTreeSet::new(),
            poll: Duration::from_millis(100),
            spin: Duration::ZERO,
            now_ns: 0,
            last_finished_ns: None,
            stats: ScheduleStats::default(),
            pending,
            hello_looked: Instant::now(),
            topics: Vec::with_capacity(proto::MAX_TOPICS),
            batch_end: None,
            longest_grant: Default::default(),
            ahead: BTreeMap::new(),
            rooms: Default::default(),
        })
    }

    /// Spins up to `spin` for the nodes' reports before sleeping (at most [`caravan::MAX_SPIN`]).
    pub fn set_spin(&mut self, spin: Duration) {
        self.spin = spin.min(caravan::MAX_SPIN);
    }

    pub fn tick_ns(&self) -> u64 {
        self.tick_ns
    }

    /// The most steps one node the scheduler waits for was granted at once, kept current
    /// while it waits: a watchdog allowing each step its time allows a grant of several
    /// periods that many times as long.
    pub fn longest_grant(&self) -> std::rc::Rc<std::cell::Cell<u64>> {
        self.longest_grant.clone()
    }

    /// Counts so far.
    pub fn stats(&self) -> ScheduleStats {
        self.stats
    }

    /// Lets nodes due at a time ≤ `end_ns` start while the time one tick earlier still runs,
    /// when they share no topic with its unfinished nodes (`overlap.rs`). The caller then
    /// advances until [`Self::next_time_ns`] is past `end_ns`: a time that started early
    /// is finished by a later [`Self::advance`].
    pub fn overlap_until(&mut self, end_ns: u64) {
        self.overlap_until = Some(end_ns);
    }

    /// Topics whose messages the caller is ready for (the recorder has looked at them): an
    /// overlapping node publishes only to these, so that a topic new to the recorder gets
    /// its tap while no later time runs.
    pub fn know_topics(&mut self, topics: impl IntoIterator<Item = u64>) {
        let known = self.known_topics.len();
        self.known_topics.extend(topics);
        if self.known_topics.len() > known {
            self.forget_rooms();
        }
    }

    /// Time of the next event, if any node is due at all: the oldest time being stepped, or
    /// the next one queued.
    pub fn next_time_ns(&self) -> Option<u64> {
        self.flights.front().map(|f| f.now_ns).or_else(|| {
            let queued = self.queue.keys().next().copied();
            let ahead = self.ahead.keys().next().copied();
            queued.into_iter().chain(ahead).min()
        })
    }

    /// Steps the next event time: grants every node due then and waits until all are done.
    /// Nodes of the time after may start meanwhile (see [`Self::overlap_until`]). Returns
    /// `None` when no node will ever be due again.
    pub fn advance(&mut self, mut watchdog: impl Watchdog) -> Result<Option<Advance>, Error> {
        if self.flights.is_empty() {
            // A time may have only nodes stepping within an earlier grant (`batch.rs`).
            let Some(now_ns) = self.next_time_ns() else {
                return Ok(None);
            };
            let due = self.queue.remove(&now_ns).unwrap_or_default();
            self.open_flight(now_ns, due);
        }
        self.now_ns = self.flights[0].now_ns;
        loop {
            self.receive_reports()?;
            self.grant_ready()?;
            let oldest = &self.flights[0];
            if oldest.waiting.is_empty() && oldest.held.is_empty() {
                break;
            }
            let waiting: Vec<usize> = self
                .flights
                .iter()
                .flat_map(|f| f.waiting.iter().copied())
                .collect();
            let names: Vec<&str> = waiting.iter().map(|&i| &*self.members[i].name).collect();
            let longest = (waiting.iter())
                .map(|&i| self.members[i].granted_steps())
                .max()
                .unwrap_or(1);
            self.longest_grant.set(longest);
            let now_ns = self.now_ns;
            let dead = watchdog(&names).map_err(|why| {
                Error::Lockstep(format!(
                    "waiting for {} to finish step at {now_ns} ns: {why}",
                    names.join(", ")
                ))
            })?;
            self.mark_dead(&dead);
            if self.hello_looked.elapsed() >= HELLO_EVERY {
                self.hello_looked = Instant::now();
                self.admit_new()?;
            }
            self.regrant_overdue()?;
            self.wait_on(false)?;
        }
        let finished = self.flights.pop_front().expect("a time is being stepped");
        self.stats.advances += 1;
        self.last_finished_ns = Some(finished.now_ns);
        // The next time's other nodes are granted by the next call, after the caller has
        // looked at what this time published (its recorder finds new topics first).
        let mut stepped: Vec<std::sync::Arc<str>> = (finished.due.iter())
            .chain(&finished.batched)
            .map(|&i| self.members[i].name.clone())
            .collect();
        stepped.sort();
        let overlapping = self
            .flights
            .front()
            .map(|f| {
                f.due
                    .difference(&f.held)
                    .flat_map(|&i| self.members[i].footprint.outputs.iter().copied())
                    .collect::<BTreeSet<u64>>()
                    .into_iter()
                    .collect()
            })
            .unwrap_or_default();
        Ok(Some(Advance {
            now_ns: finished.now_ns,
            stepped,
            published: finished.published.into_iter().collect(),
            overlapping,
        }))
    }

    fn open_flight(&mut self, now_ns: u64, due: BTreeSet<usize>) {
        let due: BTreeSet<usize> = due
            .into_iter()
            .filter(|&i| self.members[i].active)
            .collect();
        let batched = self.ahead.remove(&now_ns).unwrap_or_default();
        // What a batch published at this time, if its report is in (else `end_batch` adds it).
        let published = (batched.iter())
            .filter(|&&i| !self.flights.iter().any(|f| f.waiting.contains(&i)))
            .flat_map(|&i| self.batch_published_at(i, now_ns))
            .collect();
        self.flights.push_back(Flight {
            now_ns,
            held: due.clone(),
            due,
            waiting: BTreeSet::new(),
            published,
            batched,
            granted_at: Instant::now(),
        });
    }

    /// Grants what may step now: every node of the oldest time, and nodes of the next time
    /// that share no topic with the oldest's unfinished nodes.
    fn grant_ready(&mut self) -> Result<(), Error> {
        let Some(oldest) = self.flights.front_mut() else {
            return Ok(());
        };
        let ready: Vec<usize> = std::mem::take(&mut oldest.held).into_iter().collect();
        self.grant_all(0, ready)?;
        let oldest = &self.flights[0];
        // Only nodes of known habits may still run: a node in its first step may open ports,
        // and an undeclared one may ask for a time between this one and the next.
        if !oldest.waiting.iter().all(|&i| self.eligible(i)) {
            return Ok(());
        }
        let next_time = oldest.now_ns + self.tick_ns;
        if self.flights.len() == 1
            && self.overlap_until.is_some_and(|end| next_time <= end)
            && self.queue.keys().next() == Some(&next_time)
            && !oldest.waiting.is_empty()
            // A message stamped between the last time and this one could wake a node
            // between this time and the next.
            && self
                .last_finished_ns
                .is_none_or(|last| last + self.tick_ns <= oldest.now_ns)
        {
            let due = self.queue.remove(&next_time).unwrap_or_default();
            self.open_flight(next_time, due);
        }
        let [oldest, next] = match self.flights.as_slices() {
            ([a, b], _) => [a, b],
            ([a], [b]) => [a, b],
            _ => return Ok(()),
        };
        let running: Vec<&Footprint> = oldest
            .waiting
            .iter()
            .map(|&i| &self.members[i].footprint)
            .collect();
        let ready: Vec<usize> = next
            .held
            .iter()
            .copied()
            .filter(|&n| {
                let member = &self.members[n];
                self.eligible(n)
                    && self.batch_room(n) < 2
                    && !oldest.waiting.contains(&n)
                    && overlap::may_start(
                        &member.footprint,
                        running.iter().copied(),
                        &oldest.published,
                        &self.known_topics,
                    )
            })
            .collect();
        if ready.is_empty() {
            return Ok(());
        }
        let waiting: Vec<usize> = oldest.waiting.iter().copied().collect();
        for i in waiting {
            self.members[i].overlapped = true;
        }
        for &n in &ready {
            self.members[n].overlapped = true;
            self.flights[1].held.remove(&n);
        }
        self.stats.overlapped_steps += ready.len() as u64;
        self.grant_all(1, ready)
    }

    /// Whether node `i` may overlap another time: it declared its topics and has stepped once.
    fn eligible(&self, i: usize) -> bool {
        let m = &self.members[i];
        m.steps > 0 && m.footprint.declared
    }

    /// Grants flight `f`'s time to `nodes`, the longest-running first.
    fn grant_all(&mut self, f: usize, mut nodes: Vec<usize>) -> Result<(), Error> {
        // Which order nodes are granted in changes nothing they see (a message is visible one
        // tick after it was sent), only how soon the slowest one starts.
        nodes.sort_by_key(|&i| std::cmp::Reverse(self.members[i].last_step));
        let now_ns = self.flights[f].now_ns;
        if !nodes.is_empty() {
            self.flights[f].granted_at = Instant::now();
        }
        let idle = self.flights.iter().all(|f| f.waiting.is_empty());
        let quiet = nodes.iter().filter(|&&i| self.members[i].quiet).count();
        let token = self.pending.as_ref().map(|p| p.granting(quiet, idle));
        // Every grant is out before the first wake-up: a container woken by its first member's
        // then finds the others' grants too, and steps them all before it sleeps again.
        for &i in &nodes {
            // Only the oldest time's nodes may take several periods: every earlier time has
            // finished, so the schedule the batch is read from is the same on a rerun.
            let times = if f == 0 {
                self.batch_times(i, now_ns)
            } else {
                Vec::new()
            };
            self.note_batch(i, now_ns, times);
            let grant = self.members[i].step_grant(now_ns, self.tick_ns, token);
            self.send(i, grant)?;
            self.flights[f].waiting.insert(i);
            // The later steps of a batch are counted when it reports (it may end early).
            self.stats.steps += 1;
        }
        // One wake-up per container: its members all look for their grants whenever it wakes
        // (`container.rs`). A container is known by its process id on this machine, so only
        // members holding this machine's count are taken together.
        let mut woken: Vec<u32> = Vec::new();
        for &i in &nodes {
            let member = &self.members[i];
            let container = if member.quiet { member.container } else { 0 };
            if container != 0 {
                if woken.contains(&container) {
                    continue;
                }
                woken.push(container);
            }
            member.wake()?;
            self.stats.wake_ups += 1;
        }
        Ok(())
    }

    /// Queues `i` at `time_ns`, or adds it to that time if it is being stepped.
    pub(crate) fn insert(&mut self, mut time_ns: u64, i: usize) -> Result<(), Error> {
        // A time its grant of several steps took (or is taking) is past for it: a message
        // that wakes it there (from a publisher that restarted or joined while the batch
        // ran, after the batch was decided) is read at its next step after the batch.
        let batch = &self.members[i].batch;
        if batch.start() < batch.end() && batch.contains(&time_ns) {
            time_ns = batch.end() + self.tick_ns;
        }
        if let Some(f) = self.flights.iter_mut().find(|f| f.now_ns == time_ns) {
            if f.due.insert(i) {
                f.held.insert(i);
            }
            return Ok(());
        }
        if let Some(newest) = self.flights.back()
            && self.flights.len() > 1
            && time_ns < newest.now_ns
        {
            if newest.waiting.is_empty() && newest.due == newest.held {
                // Nothing of the next time started yet: it goes back to the queue.
                let newest = self.flights.pop_back().expect("two times");
                self.queue
                    .entry(newest.now_ns)
                    .or_default()
                    .extend(newest.due);
            } else {
                // The overlap rule admits only nodes whose events fall on the tick; say so
                // loudly rather than step out of order.
                return Err(Error::Lockstep(format!(
                    "node '{}' is due at {time_ns} ns, after {} ns started",
                    self.members[i].name, newest.now_ns
                )));
            }
        }
        self.queue.entry(time_ns).or_default().insert(i);
        Ok(())
    }

    /// Stops waiting for nodes whose process died; they rejoin when they say hello again.
    fn mark_dead(&mut self, dead: &[String]) {
        for name in dead {
            if let Some(&i) = self.by_hash.get(&proto::name_hash(name)) {
                self.forget_rooms();
                self.members[i].active = false;
                self.members[i].overlapped = false;
                // A batch it had not reported: none of its steps counts.
                let batching = (self.flights.iter()).any(|f| f.waiting.contains(&i))
                    && self.members[i].batch.start() < self.members[i].batch.end();
                for f in &mut self.flights {
                    // Not stepped at that time after all: a restart may be due there again.
                    if f.waiting.remove(&i) | f.held.remove(&i) {
                        f.due.remove(&i);
                    }
                    if batching {
                        f.batched.retain(|&j| j != i);
                    }
                }
                if batching {
                    // None of its batch's steps counts: a restart starts at the first.
                    let start = *self.members[i].batch.start();
                    self.members[i].batch = start..=start;
                    self.ahead.retain(|_, nodes| {
                        nodes.retain(|&j| j != i);
                        !nodes.is_empty()
                    });
                }
            }
        }
    }

    /// A grant (or its report) may have been lost; nodes answer repeats safely.
    fn regrant_overdue(&mut self) -> Result<(), Error> {
        for f in 0..self.flights.len() {
            if self.flights[f].granted_at.elapsed() <= REGRANT_AFTER {
                continue;
            }
            let now_ns = self.flights[f].now_ns;
            let waiting: Vec<usize> = self.flights[f].waiting.iter().copied().collect();
            let token = self.pending.as_ref().map(Pending::token);
            for i in waiting {
                // Counted once, when first granted: if that grant was lost, this one is the
                // step and is taken off the count; else the node answers it as a repeat.
                self.grant(i, self.members[i].step_grant(now_ns, self.tick_ns, token))?;
            }
            self.flights[f].granted_at = Instant::now();
        }
        Ok(())
    }

    /// Between advances: notes deaths and restarts reported by the watchdog.
    pub fn poll_members(&mut self, mut watchdog: impl Watchdog) -> Result<(), Error> {
        let dead = watchdog(&[]).map_err(Error::Lockstep)?;
        self.mark_dead(&dead);
        self.admit_new()
    }

    pub(crate) fn schedule_after(
        &mut self,
        i: usize,
        now_ns: u64,
        published: &[u64],
    ) -> Result<(), Error> {
        let period = self.members[i].period_ns;
        if period > 0 {
            self.insert(now_ns + period, i)?;
        }
        for topic in published {
            let woken = self.subscribers.get(topic).cloned().unwrap_or_default();
            for j in woken {
                self.insert(now_ns + self.tick_ns, j)?;
            }
        }
        Ok(())
    }

    /// Sends node `i` its grant, without waking it.
    fn send(&mut self, i: usize, grant: Grant) -> Result<(), Error> {
        let in_slot = self.members[i].send(grant, self.pending.as_ref())?;
        self.stats.slot_grants += in_slot as u64;
        Ok(())
    }

    fn grant(&mut self, i: usize, grant: Grant) -> Result<(), Error> {
        self.send(i, grant)?;
        self.members[i].wake()
    }

    /// Tells every node the run is over.
    pub fn stop_all(&mut self) -> Result<(), Error> {
        let now_ns = self.flights.back().map_or(self.now_ns, |f| f.now_ns);
        for i in 0..self.members.len() {
            if self.members[i].active {
                self.grant(i, Grant::stop(now_ns, self.tick_ns))?;
            }
        }
        Ok(())
    }

    pub(crate) fn wait_on(&self, hello: bool) -> Result<(), Error> {
        if !hello
            && spin_on(
                || self.reports_in(),
                &self.done_listener,
                self.spin,
                proto::DONE,
            )?
        {
            return Ok(());
        }
        let listener = if hello {
            &self.hello_listener
        } else {
            &self.done_listener
        };
        wait_events(listener, self.poll)
    }
}
