use crate::FixedString;
use crate::describe::Describe;
use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};
use serde::Serialize;

/// Execution statistics of one node, published on `status` at 1 Hz and on exit.
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::NodeStatus")]
pub struct NodeStatus {
    pub node: FixedString<64>,
    pub host: FixedString<32>,
    /// Nominal period of a periodic node, ns; 0 for a node stepped by messages.
    pub period_ns: u64,
    pub steps: u64,
    /// Steps that started more than one period late, or ran longer than one period.
    pub deadline_misses: u64,
    /// Deviation of the actual step period from the nominal one, ns.
    pub jitter_p50_ns: u64,
    pub jitter_p99_ns: u64,
    pub jitter_max_ns: u64,
    /// Wall-clock time spent inside the step function, ns.
    pub compute_mean_ns: u64,
    pub compute_p99_ns: u64,
    pub compute_max_ns: u64,
    /// Messages reported lost by this node's subscribers (sequence gaps).
    pub messages_missed: u64,
    /// Simulated time of the last step, ns.
    pub sim_time_ns: u64,
    /// 1 while running, 0 in the final report sent on exit.
    pub running: u32,
    pub _reserved: u32,
    /// Resident memory of the node's process, KiB (Linux's /proc/self/statm; 0 elsewhere).
    pub rss_kib: u64,
    /// CPU time the stepping thread spent inside the step function, mean, ns: what a host's
    /// `cpu_slowdown` scales. From the steps whose CPU clock was read: every step under a
    /// slowdown in lockstep (and every step of a Python node), else each of the first 64 and
    /// then one in 8 at random, the later ones standing for all the later steps.
    pub compute_cpu_mean_ns: u64,
}
