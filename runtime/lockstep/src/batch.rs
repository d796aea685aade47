//! Batches: a node granted several periods (or messages) at once, when none of its inputs
//! can change meanwhile.
//!
//! A node's step at s reads the messages stamped up to s − tick. If no node that publishes
//! to its inputs can step before some time H, the node's steps at s, s + period, … up to H
//! read exactly what they would read granted one at a time: the node may take them all on
//! one grant, and wake (and wake the scheduler) once instead of once per period. The
//! physics, whose set-points change only when an agent steps, steps five ticks per grant in
//! the convoy instead of one.
//!
//! A node stepped by messages (`Trigger::OnMessage`) is batched the same way over the times
//! it is due up to H: a batch of its triggers published ahead, the scheduler knows each
//! message's time from that batch's report, and the node finds the messages waiting in its
//! buffer. It steps at each time one shows (its stamp plus a tick), the times the scheduler
//! noted for the batch (`Member::batch_times`). Only a node that reads nothing but the
//! topics stepping it: a message of another topic would step it at a time the scheduler
//! does not know. For a periodic
//! reader of its topics, how many messages that reader has not read yet depends on when
//! the node stepped: the node's steps since one reader period and a tick before the batch
//! (kept in `Member::recent`), the batch's and [`SLACK`] must fit in the buffer
//! ([`Scheduler::unread_room`]). The convoy's odometry, stepped by the wheel encoders' 50 Hz
//! ticks that the sensors publish five periods at a time, takes their steps two and three
//! at a time.
//!
//! What it publishes ahead waits in its readers' buffers, hidden until its time by their
//! stamps (`caravan::Subscriber`), and in the recorder's taps until that time ends. So:
//! - a batch never runs past the run's end, and only its first step's time waits for it:
//!   every later time of the batch is finished when its grant's is;
//! - its steps, with what a reader has not read yet (one message a period of the reader's,
//!   or one if the reader is stepped by each message it reads) and [`SLACK`], fit in the
//!   smallest buffer of its topics (`Hello::output_depth`): a reader, even one stepping beside
//!   the batch's first step, finds every message it would find granted one period at a time.
//!   (A reader that falls behind a topic loses its oldest messages either way; only which and
//!   how many may differ.) A step that sends one
//!   topic two messages ends the batch there ([`Done::BURST`]), and the node is batched no
//!   more;
//! - no other node publishes to its topics;
//! - a node stepped by its messages is stepped at each time one was published: the batch's
//!   report says which of its steps published where ([`Done::STEPS`]);
//! - every topic it publishes to is known to the recorder;
//! - every other node is running, declared its topics and holds this machine's count of
//!   quiet steps, and each one publishing to its inputs has a known next step: a periodic
//!   one's from the schedule (one due as often as the node leaves it no room), a node
//!   stepped by messages not before the next tick.
//!
//! The decision reads only the schedule as it stands when the batch's time is the oldest
//! (every earlier time finished), and a node that may be batched is never granted early
//! beside an earlier time (`overlap.rs`), so reruns take the same batches. A restarted node
//! rejoins after the steps of its last batch. A node that opens
//! a port after joining while a batch runs stops the run, as under overlap. (A restarted
//! node rejoins at a time the wall clock decides: a batch is not cut short for it.)

use crate::members::RECENT;
use crate::overlap;
use crate::scheduler::Scheduler;
use caravan::Error;
use caravan::lockstep::Report;
use caravan_schemas::lockstep::{Done, MAX_TOPICS};

/// Most periods one grant may hold: a batch is reported as a whole.
const MAX_STEPS: u64 = 32;

/// Room kept in each reader's buffer beyond the batch's messages: a step that sends one topic
/// up to `SLACK + 1` messages (and so ends its batch, `Done::BURST`) loses nothing.
const SLACK: u64 = 2;

impl Scheduler {
    /// Lets a periodic node be granted several periods at once, up to `end_ns` (the run's
    /// end), when none of its inputs can change meanwhile (see `batch.rs`).
    pub fn batch_until(&mut self, end_ns: u64) {
        self.batch_end = Some(end_ns);
        self.forget_rooms();
    }

    /// The most periods node `i` could take on one grant, whatever the time: 1 if it cannot
    /// batch. What does not depend on the time is decided here; a node this allows more
    /// than one is never overlapped, so that its batches do not depend on which of two
    /// times it was granted in.
    pub(crate) fn batch_room(&self, i: usize) -> u64 {
        self.room(i, true)
    }

    /// Forgets every node's room: what it reads changed (a node joined, died, stepped for the
    /// first time, reported into its slot, burst or opened a topic late; the recorder learned
    /// topics; batching was turned on).
    pub(crate) fn forget_rooms(&mut self) {
        self.rooms.get_mut().clear();
    }

    /// [`Self::batch_room`], looking at the publishers of its inputs if `writers` (a
    /// publisher due as often as it leaves room only if it batches too). Kept until
    /// [`Self::forget_rooms`]: it reads only what changes there, and is asked at every grant.
    fn room(&self, i: usize, writers: bool) -> u64 {
        let known = self
            .rooms
            .borrow()
            .get(i)
            .map_or(0, |r| r[writers as usize]);
        if known > 0 {
            // In debug builds every test's schedule checks that nothing it reads changed
            // without `forget_rooms`.
            debug_assert_eq!(
                known,
                self.fresh_room(i, writers),
                "room of node {i} (writers: {writers})"
            );
            return known;
        }
        let room = self.fresh_room(i, writers);
        let mut rooms = self.rooms.borrow_mut();
        if rooms.len() <= i {
            rooms.resize(self.members.len(), [0; 2]);
        }
        rooms[i][writers as usize] = room;
        room
    }

    /// [`Self::room`], worked out.
    fn fresh_room(&self, i: usize, writers: bool) -> u64 {
        let m = &self.members[i];
        let (inputs, outputs) = (&m.footprint.inputs, &m.footprint.outputs);
        // Stepped by messages: its steps are the times its messages arrive.
        let on_messages = m.period_ns == 0 && m.triggered;
        let (period, depth) = (m.period_ns, m.output_depth as u64);
        let eligible = self.batch_end.is_some()
            && (period > 0 && !m.triggered || on_messages)
            && !m.bursty
            && m.quiet
            && m.slot_grants
            && m.steps > 0
            && m.footprint.declared
            && depth >= 2 + SLACK
            && (on_messages || !outputs.is_empty())
            // Stepped by messages, it steps when any message it holds shows: the scheduler
            // knows those times only for the topics that step it.
            && (!on_messages
                || (inputs.iter()).all(|t| self.subscribers.get(t).is_some_and(|w| w.contains(&i))))
            && outputs.iter().all(|t| self.known_topics.contains(t))
            // The report's pairs (and the status topic's) must fit when nodes are stepped by
            // its topics.
            && ((outputs.len() + 1) * 2 <= MAX_TOPICS
                || !outputs.iter().any(|t| self.subscribers.contains_key(t)));
        if !eligible {
            return 1;
        }
        let mut steps = (depth - 1 - SLACK).min(MAX_STEPS);
        for (j, other) in self.members.iter().enumerate() {
            if j == i {
                continue;
            }
            // A node that may restart (or that exited), or whose steps or topics are not
            // known here, may publish anywhere at any time.
            if !other.active || !other.quiet || !other.footprint.declared {
                return 1;
            }
            let theirs = &other.footprint;
            // Another publisher of its topics: their messages share the readers' buffers.
            if !overlap::disjoint(&theirs.outputs, outputs) {
                return 1;
            }
            // A publisher of its inputs due as often as it is leaves no room between its
            // steps, unless it runs ahead in batches itself.
            if writers
                && !overlap::disjoint(&theirs.outputs, inputs)
                && !(other.period_ns > period
                    || other.period_ns == 0 && period <= self.tick_ns
                    || other.period_ns > 0 && self.room(j, false) >= 2)
            {
                return 1;
            }
            if !overlap::disjoint(&theirs.inputs, outputs) {
                // A reader: it finds up to `gap` unread messages of each topic when it
                // steps, one more if it steps beside the batch's first step, and the
                // batch's ahead of them.
                let gap = if other.period_ns > 0 && on_messages {
                    // How many it has not read depends on when the node stepped: counted
                    // at the time ([`Self::unread_room`]).
                    continue;
                } else if other.period_ns > 0 {
                    other.period_ns.div_ceil(period)
                } else if (theirs.inputs.iter())
                    .filter(|t| outputs.binary_search(t).is_ok())
                    .all(|t| self.subscribers.get(t).is_some_and(|w| w.contains(&j)))
                {
                    // Stepped by each message of what it reads of the node's.
                    1
                } else {
                    return 1;
                };
                // One that falls behind loses its oldest messages either way (only which and
                // how many may differ); its newest stays.
                if gap <= depth {
                    steps = steps.min(depth.saturating_sub(gap + SLACK));
                }
            }
        }
        steps.max(1)
    }

    /// The times after `now_ns` at which node `i`, due at `now_ns` (the oldest time being
    /// stepped), may step on the same grant, in order: none if only that one.
    pub(crate) fn batch_times(&self, i: usize, now_ns: u64) -> Vec<u64> {
        let (Some(end), steps) = (self.batch_end, self.batch_room(i)) else {
            return Vec::new();
        };
        if steps < 2 {
            return Vec::new();
        }
        let m = &self.members[i];
        let period = m.period_ns;
        let mut horizon = match period {
            0 => end,
            _ => end.min(now_ns + (steps - 1) * period),
        };
        for (j, other) in self.members.iter().enumerate() {
            if j != i && !overlap::disjoint(&other.footprint.outputs, &m.footprint.inputs) {
                horizon = horizon.min(self.next_due(j, now_ns));
            }
        }
        if period > 0 {
            return (1..)
                .map(|k| now_ns + k * period)
                .take_while(|&t| t <= horizon)
                .collect();
        }
        // Stepped by messages: the times it is due, as many as its readers leave room for.
        let room = steps.min(self.unread_room(i, now_ns)) as usize;
        let mut times = self.due_times(i, now_ns, horizon);
        times.truncate(room.saturating_sub(1));
        times
    }

    /// For a node `i` stepped by messages, due at `now_ns`: the most steps it may take on one
    /// grant for the periodic readers of its topics. A reader finds, at its first step from
    /// `now_ns` on, every message sent since one period and a tick before that (the messages
    /// it read at its step before are older): the node's steps since then, the batch's, and
    /// [`SLACK`] must fit in the buffer. One that already falls behind loses its oldest either
    /// way.
    fn unread_room(&self, i: usize, now_ns: u64) -> u64 {
        let m = &self.members[i];
        let depth = m.output_depth as u64;
        let mut room = u64::MAX;
        for other in &self.members {
            if other.period_ns == 0
                || overlap::disjoint(&other.footprint.inputs, &m.footprint.outputs)
            {
                continue;
            }
            let since = now_ns.saturating_sub(other.period_ns + self.tick_ns);
            if m.recent.len() == RECENT && m.recent.front().is_some_and(|&t| t > since) {
                // More steps in the window than it keeps: it cannot tell whether they fit.
                return 1;
            }
            let unread = (m.recent.iter())
                .filter(|&&t| t > since && t < now_ns)
                .count() as u64;
            if unread < depth {
                room = room.min(depth.saturating_sub(unread + SLACK));
            }
        }
        room
    }

    /// The times after `now_ns` up to `last_ns` at which node `i` is due, in order.
    fn due_times(&self, i: usize, now_ns: u64, last_ns: u64) -> Vec<u64> {
        if last_ns <= now_ns {
            return Vec::new();
        }
        let in_flights = (self.flights.iter())
            .filter(|f| f.due.contains(&i))
            .map(|f| f.now_ns);
        let queued = (self.queue.range(now_ns + 1..=last_ns))
            .filter(|(_, due)| due.contains(&i))
            .map(|(&t, _)| t);
        let times: std::collections::BTreeSet<u64> = in_flights
            .chain(queued)
            .filter(|&t| t > now_ns && t <= last_ns)
            .collect();
        times.into_iter().collect()
    }

    /// The earliest time ≥ `now_ns` (the oldest time being stepped) node `j` may step.
    fn next_due(&self, j: usize, now_ns: u64) -> u64 {
        let in_flight = self.flights.iter().find(|f| f.due.contains(&j));
        let queued = self.queue.iter().find(|(_, due)| due.contains(&j));
        let known = in_flight
            .map(|f| f.now_ns)
            .or(queued.map(|(&t, _)| t))
            .unwrap_or(u64::MAX);
        if self.members[j].period_ns == 0 {
            // Stepped by messages: any step from this time on may wake it at the next tick.
            known.min(now_ns + self.tick_ns)
        } else {
            known
        }
    }

    /// Notes that node `i` steps on the grant of `now_ns` at `times` too ([`Self::batch_times`];
    /// a node stepped by messages is then no more due at them).
    pub(crate) fn note_batch(&mut self, i: usize, now_ns: u64, times: Vec<u64>) {
        for &t in &times {
            match self.flights.iter_mut().find(|f| f.now_ns == t) {
                Some(f) => {
                    if f.due.remove(&i) {
                        f.held.remove(&i);
                    }
                    f.batched.push(i);
                }
                None => {
                    if let Some(due) = self.queue.get_mut(&t) {
                        due.remove(&i);
                        if due.is_empty() {
                            self.queue.remove(&t);
                        }
                    }
                    self.ahead.entry(t).or_default().push(i);
                }
            }
        }
        self.members[i].batch = now_ns..=times.last().copied().unwrap_or(now_ns);
        self.members[i].batch_times = times;
    }

    /// The time of the grant node `i`'s report of a step at `reported_ns` answers: its
    /// batch's first when it falls in it.
    pub(crate) fn granted_at(&self, i: usize, reported_ns: u64) -> u64 {
        let batch = &self.members[i].batch;
        if batch.start() < batch.end() && batch.contains(&reported_ns) {
            *batch.start()
        } else {
            reported_ns
        }
    }

    /// Takes the report ending node `i`'s batch: the later times of the batch learn what it
    /// published then (`steps`, the report's pairs, else all of it at each), and steps it did
    /// not take (it ended early) are taken off them; a node stepped by messages is due then
    /// again.
    pub(crate) fn end_batch(
        &mut self,
        i: usize,
        report: &Report,
        steps: Option<&[(u64, u32)]>,
    ) -> Result<(), Error> {
        let batch = self.members[i].batch.clone();
        if report.flags & Done::BURST != 0 && !self.members[i].bursty {
            self.members[i].bursty = true;
            self.forget_rooms();
            tracing::debug!(
                "node '{}' sent one topic two messages in its step at {} ns: it is granted \
                 one period at a time from now on",
                self.members[i].name,
                report.now_ns
            );
        }
        if batch.start() == batch.end() {
            return Ok(());
        }
        let published: Vec<(u64, u32)> = match steps {
            Some(steps) => steps.to_vec(),
            None => report.published.iter().map(|&t| (t, u32::MAX)).collect(),
        };
        let member = &self.members[i];
        for f in self.flights.iter_mut() {
            if f.now_ns > *batch.start() && f.batched.contains(&i) {
                if f.now_ns <= report.now_ns {
                    let step = member.step_of(f.now_ns);
                    f.published.extend(published_at(&published, step));
                } else {
                    f.batched.retain(|&j| j != i);
                }
            }
        }
        self.ahead.retain(|&t, nodes| {
            if t > report.now_ns {
                nodes.retain(|&j| j != i);
            }
            !nodes.is_empty()
        });
        let (taken, untaken): (Vec<u64>, Vec<u64>) =
            std::mem::take(&mut self.members[i].batch_times)
                .into_iter()
                .partition(|&t| t <= report.now_ns);
        self.stats.steps += taken.len() as u64;
        self.stats.batched_steps += taken.len() as u64;
        let member = &mut self.members[i];
        member.batch_published = published;
        member.batch = *batch.start()..=report.now_ns;
        member.batch_times = taken;
        if member.period_ns == 0 {
            // Their messages still wait for it.
            for t in untaken {
                self.insert(t, i)?;
            }
        }
        Ok(())
    }

    /// What node `i`'s last batch published at `now_ns`, one of its times after the first.
    pub(crate) fn batch_published_at(
        &self,
        i: usize,
        now_ns: u64,
    ) -> impl Iterator<Item = u64> + '_ {
        let m = &self.members[i];
        published_at(&m.batch_published, m.step_of(now_ns))
    }

    /// Schedules what node `i`'s batch of `first_ns` up to `last_ns` woke: itself a period
    /// after its last step, and the nodes stepped by a topic a tick after each step that
    /// published there.
    pub(crate) fn schedule_batch_after(
        &mut self,
        i: usize,
        first_ns: u64,
        last_ns: u64,
        steps: &[(u64, u32)],
    ) -> Result<(), Error> {
        let period = self.members[i].period_ns;
        if period > 0 {
            self.insert(last_ns + period, i)?;
        }
        for &(topic, bits) in steps {
            let Some(woken) = self.subscribers.get(&topic).cloned() else {
                continue;
            };
            for step in (0..32).filter(|j| bits & (1 << j) != 0) {
                let at = match step {
                    0 => first_ns,
                    k => match self.members[i].batch_times.get(k - 1) {
                        Some(&at) => at,
                        None => break,
                    },
                };
                if at > last_ns {
                    break;
                }
                for &j in &woken {
                    self.insert(at + self.tick_ns, j)?;
                }
            }
        }
        Ok(())
    }
}

/// The topics of `published` (topic, bit j for each step j that published there) published
/// at step `step`.
pub(crate) fn published_at(published: &[(u64, u32)], step: u64) -> impl Iterator<Item = u64> + '_ {
    let bit = 1u32.checked_shl(step as u32).unwrap_or(0);
    (published.iter())
        .filter(move |(_, bits)| bits & bit != 0)
        .map(|&(t, _)| t)
}

/// A batch's report's pairs of topic and steps ([`Done::STEPS`]), if it has them.
pub(crate) fn steps_of(report: &Report) -> Option<Vec<(u64, u32)>> {
    (report.flags & Done::STEPS != 0).then(|| {
        (report.published.chunks_exact(2))
            .map(|pair| (pair[0], pair[1] as u32))
            .collect()
    })
}
