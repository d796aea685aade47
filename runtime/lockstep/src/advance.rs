//! What the scheduler reports: each advance of simulated time and the run's counts, and the
//! watchdog it consults while it waits.

/// One advance of simulated time.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Advance {
    pub now_ns: u64,
    /// Names of the nodes that stepped, sorted (shared with the scheduler's, not copied at
    /// every advance).
    pub stepped: Vec<std::sync::Arc<str>>,
    /// Hashes of the topics published in this step, sorted.
    pub published: Vec<u64>,
    /// Topics (hashes) published by nodes already stepping at the next time (see
    /// [`crate::Scheduler::overlap_until`]): none of their messages belongs to `now_ns`, and the
    /// caller must leave them to that time.
    pub overlapping: Vec<u64>,
}

/// What the scheduler did over a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ScheduleStats {
    /// Times of simulated time stepped.
    pub advances: u64,
    /// Steps granted (all nodes, all times).
    pub steps: u64,
    /// Steps granted while the time before was still running ([`crate::Scheduler::overlap_until`]).
    pub overlapped_steps: u64,
    /// Wake-ups sent with grants: one per node granted, but one per batch for a container's
    /// members. (Absent from a report of a build before it: 0.)
    #[serde(default)]
    pub wake_ups: u64,
    /// Reports read from the nodes' slots in the shared page rather than from `Done`
    /// samples (`caravan::lockstep::Report`). (0 when read from a report of a build before it.)
    #[serde(default)]
    pub slot_reports: u64,
    /// Grants written into the nodes' slots rather than sent as samples, stops included.
    /// (0 when read from a report of a build before it.)
    #[serde(default)]
    pub slot_grants: u64,
    /// Steps taken within a grant of an earlier period (a grant of several periods,
    /// `caravan_lockstep` "batches"), counted in `steps` too. (0 when read from a report of a
    /// build before it.)
    #[serde(default)]
    pub batched_steps: u64,
}

/// Consulted while the scheduler waits, with the names of the nodes it waits for: returns the
/// names of nodes whose process died since the last call, or `Err` to abort the run.
pub trait Watchdog: FnMut(&[&str]) -> Result<Vec<String>, String> {}
impl<F: FnMut(&[&str]) -> Result<Vec<String>, String>> Watchdog for F {}
