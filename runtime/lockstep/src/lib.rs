//! The lockstep scheduler: owns a group's simulated time, grants its nodes' steps and
//! collects their reports. The launcher runs one per lockstep group; the protocol it speaks,
//! and the node's side of it, are `caravan::lockstep`'s.
//!
//! Overlap: nodes due one tick later may start while an earlier time is still running, if they
//! share no topic with the nodes still running there (`overlap.rs`). Nothing they could see
//! differs, so recordings stay the same bytes; the two cores are kept busy instead of waiting
//! for the slowest node of every time (typically the physics) before anything else starts.
//!
//! Batches: a periodic node whose inputs cannot change before a later time is granted every
//! period up to then at once (`batch.rs`), and it and the scheduler wake once for them.

mod admission;
mod advance;
mod batch;
mod members;
mod overlap;
mod reports;
mod scheduler;

pub use advance::{Advance, ScheduleStats, Watchdog};
pub use caravan::lockstep::Pending;
pub use scheduler::Scheduler;
