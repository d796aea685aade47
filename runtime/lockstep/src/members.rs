//! What the scheduler keeps of each node and of each time being stepped.

use crate::overlap::Footprint;
use caravan::Error;
use caravan::lockstep::Pending;
use caravan::lockstep::control::Pub;
use caravan_schemas::lockstep::Grant;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::prelude::*;
use std::collections::BTreeSet;
use std::time::{Duration, Instant};

/// A node in the schedule.
pub(crate) struct Member {
    /// Shared with every [`crate::Advance`] that names it.
    pub(crate) name: std::sync::Arc<str>,
    /// False after the process died, until it says hello again (a restart).
    pub(crate) active: bool,
    pub(crate) period_ns: u64,
    /// Whether it steps when it joins: it has a period, or (neither a period nor triggers)
    /// it is scheduled by its own wake-ups and steps once to ask for the first.
    pub(crate) steps_on_joining: bool,
    /// The topics it touches, for overlapping it with nodes of another time.
    pub(crate) footprint: Footprint,
    /// Steps reported since it joined: a node overlaps only after its first, in which many
    /// nodes still open ports.
    pub(crate) steps: u64,
    /// A node of a later time started while this one stepped.
    pub(crate) overlapped: bool,
    /// When it was last granted a step (wall clock).
    pub(crate) granted_at: Instant,
    /// Wall time from its last grant to its report: the longest-running nodes are granted
    /// first, so the step that bounds the advance starts soonest.
    pub(crate) last_step: Duration,
    /// It holds the scheduler's count of quiet steps (`pending.rs`): its steps are granted
    /// quiet.
    pub(crate) quiet: bool,
    /// The process id of its container on this machine (its hello's), 0 if none: a
    /// container's members are woken once per batch of grants.
    pub(crate) container: u32,
    /// Its report slot in the page of quiet steps (`caravan::lockstep::Pending::give_slot`),
    /// if it holds the page and a slot was free.
    pub(crate) slot: Option<usize>,
    /// It reported into its slot, so it knows it: its grants are written there too.
    pub(crate) slot_grants: bool,
    pub(crate) grant: Pub<Grant>,
    pub(crate) grant_notifier: Notifier<ipc::Service>,
    /// Stepped by messages on a topic (`Hello::triggers`).
    pub(crate) triggered: bool,
    /// The smallest buffer depth of its outputs (`Hello::output_depth`), 0 if unknown.
    pub(crate) output_depth: u32,
    /// A step of it sent two messages to one topic (`Done::BURST`): never batched again.
    pub(crate) bursty: bool,
    /// Its last grant's steps, first and last (the same for one step): see `batch.rs`.
    pub(crate) batch: std::ops::RangeInclusive<u64>,
    /// The topics of its last report of several periods, each with a bit for each step of
    /// the batch that published there, for the times of the batch after the first.
    pub(crate) batch_published: Vec<(u64, u32)>,
    /// The times of its last grant's steps after the first (empty for one step).
    pub(crate) batch_times: Vec<u64>,
    /// The times of its last steps, oldest first (at most [`RECENT`]): how many messages a
    /// reader of its topics may not have read yet when a node stepped by messages is granted
    /// several at once (`batch.rs`).
    pub(crate) recent: std::collections::VecDeque<u64>,
}

/// How many of a node's last step times [`Member::recent`] keeps: a node with more steps in
/// a reader's window is not batched (`batch.rs`).
pub(crate) const RECENT: usize = 64;

impl Member {
    /// Its grant of a step at `now_ns`: quiet, under `token`, if it holds the count of quiet
    /// steps (`pending.rs`).
    /// A grant of several periods ([`Self::batch`]) if it was granted them at `now_ns`.
    pub(crate) fn step_grant(&self, now_ns: u64, tick_ns: u64, token: Option<u32>) -> Grant {
        let mut grant = Grant::step(now_ns, tick_ns);
        if *self.batch.start() == now_ns {
            grant = grant.steps_until(*self.batch.end());
        }
        match token {
            Some(token) if self.quiet => grant.quiet(token),
            _ => grant,
        }
    }

    /// How many steps its last grant holds.
    pub(crate) fn granted_steps(&self) -> u64 {
        self.batch_times.len() as u64 + 1
    }

    /// Which step of its last grant was at `now_ns` (the bit of its report's `Done::STEPS`
    /// that stands for it); `u64::MAX` if none.
    pub(crate) fn step_of(&self, now_ns: u64) -> u64 {
        if *self.batch.start() == now_ns {
            return 0;
        }
        (self.batch_times.iter())
            .position(|&t| t == now_ns)
            .map_or(u64::MAX, |k| k as u64 + 1)
    }

    /// Notes that it stepped at `now_ns`.
    pub(crate) fn stepped_at(&mut self, now_ns: u64) {
        if self.recent.len() == RECENT {
            self.recent.pop_front();
        }
        self.recent.push_back(now_ns);
    }

    /// Sends its grant, without waking it ([`Self::wake`]): into its slot of `page` once it
    /// reads grants there, else as a sample. True if into its slot.
    pub(crate) fn send(&mut self, grant: Grant, page: Option<&Pending>) -> Result<bool, Error> {
        self.granted_at = Instant::now();
        match (self.slot, page) {
            (Some(slot), Some(page)) if self.slot_grants => {
                page.write_grant(slot, grant);
                Ok(true)
            }
            _ => caravan::lockstep::control::send(&self.grant, grant, &self.name).map(|()| false),
        }
    }

    /// Wakes it for the grant it was sent.
    pub(crate) fn wake(&self) -> Result<(), Error> {
        self.grant_notifier
            .notify()
            .map_err(|e| Error::transport(&self.name, e))?;
        Ok(())
    }
}

/// One time being stepped.
pub(crate) struct Flight {
    pub(crate) now_ns: u64,
    /// Every node stepping at this time.
    pub(crate) due: BTreeSet<usize>,
    /// Due, not granted yet: waiting for nodes of the earlier time it shares topics with.
    pub(crate) held: BTreeSet<usize>,
    /// Granted, report not in yet.
    pub(crate) waiting: BTreeSet<usize>,
    pub(crate) published: BTreeSet<u64>,
    /// Nodes that step at this time within a grant of an earlier one (`batch.rs`).
    pub(crate) batched: Vec<usize>,
    /// Last (re)grant of the waiting nodes, for repeating lost grants.
    pub(crate) granted_at: Instant,
}
