//! Messages of the lockstep protocol between the scheduler and each node.
//!
//! A node announces itself with [`Hello`], then waits for a [`Grant`] on its own grant service,
//! steps at the granted simulated time and answers with [`Done`]. See `caravan::lockstep`.

use crate::describe::Describe;
use crate::{FixedString, FixedVec};
use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};
use serde::Serialize;

/// Most topics a node may trigger on or publish to in one step, as seen by the scheduler.
/// Enough for one physics process publishing three topics for each of 64+ robots.
pub const MAX_TOPICS: usize = 512;

/// Service where nodes announce themselves.
pub const HELLO: &str = "caravan/lockstep/hello";
/// Service where nodes report a finished step.
pub const DONE: &str = "caravan/lockstep/done";

/// Service on which the scheduler grants steps to `node`.
pub fn grant_service(node: &str) -> String {
    format!("caravan/lockstep/grant/{node}")
}

/// Stable 64-bit FNV-1a hash used to name nodes and topics in protocol messages.
pub const fn name_hash(name: &str) -> u64 {
    let bytes = name.as_bytes();
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    let mut i = 0;
    while i < bytes.len() {
        hash ^= bytes[i] as u64;
        hash = hash.wrapping_mul(0x0100_0000_01b3);
        i += 1;
    }
    hash
}

#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend, PlacementDefault, Serialize, Describe)]
#[type_name("caravan::lockstep::Hello")]
pub struct Hello {
    pub node: FixedString<64>,
    /// The process id of the container the node is a member of, 0 for a node that is not.
    /// A container's members all look for their grants when one of them is woken, so the
    /// scheduler wakes a container once per batch of grants. (It sits in what was padding:
    /// the layout is otherwise unchanged.)
    pub container: u32,
    /// Period of a periodic node, ns; 0 for a node stepped only by messages.
    pub period_ns: u64,
    /// Hashes of the topics whose messages wake this node.
    pub triggers: FixedVec<u64, MAX_TOPICS>,
    /// Hashes of every topic the node reads (with `declared`).
    pub inputs: FixedVec<u64, MAX_TOPICS>,
    /// Hashes of every topic the node publishes to (with `declared`).
    pub outputs: FixedVec<u64, MAX_TOPICS>,
    /// 1: `inputs` and `outputs` are all the topics the node will ever touch, and its
    /// messages are stamped with the granted time; the scheduler may then step it while
    /// nodes it shares no topic with finish an earlier time. 0 (unknown): never overlapped.
    pub declared: u32,
    /// The token of this machine's count of quiet steps (`caravan::lockstep::Pending`), which
    /// the node holds open: it may then be granted quiet steps. 0: always notify.
    pub quiet: u32,
    /// The smallest buffer depth of the topics it publishes to (messages a subscriber
    /// holds), `u32::MAX` if it publishes to none, 0 if it does not say (it takes one step a
    /// grant): a node may be granted several steps at once ([`Grant::until_ns`]) only while
    /// each of its readers can hold what it publishes ahead of them.
    pub output_depth: u32,
    pub _reserved: u32,
}

/// Permission to step at simulated time `now_ns`, and at its later times up to `until_ns`
/// (a periodic node's periods, a node stepped by messages the times they show).
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, Eq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::lockstep::Grant")]
pub struct Grant {
    pub now_ns: u64,
    /// Minimum delivery delay: a message stamped t is visible from t + tick_ns on.
    pub tick_ns: u64,
    /// 1: the run is over; the node finishes instead of stepping.
    pub stop: u32,
    /// Not 0: a quiet step, counted in the count of this token (the node's `Hello::quiet`):
    /// the node takes it off the count before reporting, and notifies only when at most one
    /// quiet step is left. 0: report and notify.
    pub quiet: u32,
    /// The last time this grant lets the node step at: a periodic node steps at `now_ns`,
    /// `now_ns` + its period, … up to `until_ns`; a node stepped by messages at `now_ns` and
    /// then whenever a message it holds shows (its stamp plus a tick) up to `until_ns`. It
    /// does not wait for a grant in between, and reports once, for its last step. The
    /// scheduler grants several steps only when none of the node's inputs can change
    /// meanwhile (`caravan_lockstep`, "batches"). 0 or `now_ns`: one step.
    pub until_ns: u64,
}

impl Grant {
    /// Permission to step at `now_ns`.
    pub fn step(now_ns: u64, tick_ns: u64) -> Self {
        Self {
            now_ns,
            tick_ns,
            stop: 0,
            quiet: 0,
            until_ns: now_ns,
        }
    }

    /// Permission to step at `now_ns` and every period after it up to `until_ns`.
    pub fn steps_until(self, until_ns: u64) -> Self {
        Self {
            until_ns: until_ns.max(self.now_ns),
            ..self
        }
    }

    /// The time of its last step: the time its report carries.
    pub fn last_ns(&self) -> u64 {
        self.until_ns.max(self.now_ns)
    }

    /// A quiet step (see [`Grant::quiet`]) counted in the count of `token`.
    pub fn quiet(self, token: u32) -> Self {
        Self {
            quiet: token,
            ..self
        }
    }

    /// The end of the run.
    pub fn stop(now_ns: u64, tick_ns: u64) -> Self {
        Self {
            now_ns,
            tick_ns,
            stop: 1,
            quiet: 0,
            until_ns: now_ns,
        }
    }
}

/// A finished step.
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend, PlacementDefault, Serialize, Describe)]
#[type_name("caravan::lockstep::Done")]
pub struct Done {
    pub node_hash: u64,
    pub now_ns: u64,
    /// A node stepped by messages asks to step again at this time (a message it holds
    /// becomes visible then: delayed by a link, or stamped later by a compute budget); 0 for
    /// none.
    pub wake_ns: u64,
    /// Hashes of the topics this step published to (a grant of several periods: see
    /// [`Done::STEPS`]).
    pub published: FixedVec<u64, MAX_TOPICS>,
    /// 1: the node's `Hello` declaration no longer holds (it opened a port after joining);
    /// the scheduler stops overlapping it.
    pub undeclared: u32,
    /// Bits ([`Done::BURST`], [`Done::STEPS`]); it was reserved, always 0.
    pub flags: u32,
}

impl Done {
    /// A step published more than one message to one topic. A grant of several periods ended
    /// at that step (`now_ns`, maybe before the grant's last), and the scheduler grants the
    /// node one period at a time from then on.
    pub const BURST: u32 = 1;
    /// The report of a grant of several steps: `published` holds pairs, a topic's hash then
    /// a word whose bit j says that the grant's step j (the first is 0; for a periodic node
    /// at `now_ns` of the grant plus j periods) published there, so that the nodes its
    /// messages step are stepped at their times.
    pub const STEPS: u32 = 2;
}
