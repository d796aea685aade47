use crate::describe::Describe;
use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};
use serde::Serialize;

/// Stamped on every message by the publisher; travels as iceoryx2's user header.
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, Eq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::Header")]
pub struct Header {
    /// Per-publisher sequence number, starting at 1; a gap means lost messages.
    pub seq: u64,
    /// Simulated time of the step that produced the message, in nanoseconds.
    pub stamp_ns: u64,
    /// Wall-clock (CLOCK_REALTIME) send time in nanoseconds, for latency tracing.
    pub send_wall_ns: u64,
    /// Identifier of the publishing node (a hash of its name, see `caravan::node_id`).
    pub source_id: u64,
}
