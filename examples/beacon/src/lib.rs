//! A message type of a user's own, declared outside Caravan: nothing in Caravan's tree knows
//! it, yet the recorder, `caravan topic echo`, `caravan topic pub` and `caravan play` read and
//! write it, from the descriptor its publisher registers with the group.

use caravan_schemas::describe::Describe;
use caravan_schemas::{FixedString, FixedVec, Vector3};
use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};
use serde::Serialize;

/// Readings kept in [`Beacon::history`].
pub const HISTORY: usize = 4;

/// A radio beacon's broadcast.
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend, PlacementDefault, Serialize, Describe)]
#[type_name("beacon::Beacon")]
pub struct Beacon {
    /// Broadcasts so far.
    pub id: u32,
    /// Signal strength, dBm.
    pub strength_dbm: f32,
    /// Where the beacon is, m, world frame.
    pub position: Vector3,
    /// What the beacon says; set with `caravan topic pub beacon/set '{"label": "…"}'`.
    pub label: FixedString<16>,
    /// The last strengths, dBm, oldest first.
    pub history: FixedVec<f64, HISTORY>,
}

/// The beacon's broadcasts.
pub const TOPIC: &str = "beacon";
/// What sets the beacon's label and position.
pub const SET: &str = "beacon/set";
