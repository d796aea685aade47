//! The lockstep protocol: simulated time granted step by step.
//!
//! Each node announces itself ([`Hello`]: its period, the topics that wake it, the topics it
//! reads and publishes), then repeats: wait for a [`Grant`] of simulated time t, step at t,
//! report [`Done`] with the topics it published. The [`Scheduler`] owns time: at each event
//! time it grants every due node at once and waits until all reported done. A message
//! published at t wakes its triggered subscribers at t + tick and is invisible to them before,
//! so runs are deterministic whatever the machine's load.
//!
//! Overlap: nodes due one tick later may start while an earlier time is still running, if they
//! share no topic with the nodes still running there (`overlap.rs`). Nothing they could see
//! differs, so recordings stay the same bytes; the two cores are kept busy instead of waiting
//! for the slowest node of every time (typically the physics) before anything else starts.
//!
//! The scheduler is the launcher's (`caravan-lockstep`); this module holds the node's side
//! ([`Client`], used by every node's executor), the count of quiet steps both sides share
//! ([`Pending`]) and the control ports both make alike ([`control`]).
//!
//! [`Hello`]: caravan_schemas::lockstep::Hello
//! [`Grant`]: caravan_schemas::lockstep::Grant
//! [`Done`]: caravan_schemas::lockstep::Done

mod client;
pub mod control;
mod pending;
mod slots;

pub(crate) use client::{Client, GrantOutcome};
pub use pending::Pending;
pub use slots::Report;
