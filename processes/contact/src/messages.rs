//! The contact a perception process estimated, as the contact-identification scenario
//! publishes it. The scenario owns the type: Caravan's tools learn its layout from the
//! descriptor the process registers with its group; its type name (`caravan::ContactEstimate`)
//! is the one recordings made before the move carry.

use caravan_schemas::describe::Describe;
use caravan_schemas::{Name, Topic, Vector3};
use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};
use serde::Serialize;

/// A contact force and its point as a perception process estimated them
/// (`robot/i/contact_estimate`), e.g. from joint torques. World frame.
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::ContactEstimate")]
pub struct ContactEstimate {
    /// The link touched; empty when no contact was found.
    pub link: Name,
    /// One of the `ContactEstimate::` constants: how the estimate was made.
    pub status: u32,
    /// The candidate links the estimate chose among (1-based, inclusive; 0 when none).
    pub first_candidate: u32,
    pub last_candidate: u32,
    pub _reserved: u32,
    /// Contact point, m; NaN when unknown.
    pub point: Vector3,
    /// N; NaN when no force was found.
    pub force: Vector3,
}

impl ContactEstimate {
    /// No contact (no joint torque above the noise).
    pub const NO_CONTACT: u32 = 0;
    /// Force and point from the measurements alone.
    pub const FOUND: u32 = 1;
    /// The force from the measurements, the point from another sensor (a fall-back).
    pub const POINT_FROM_OTHER_SENSOR: u32 = 2;
    /// The force, but no point.
    pub const NO_POINT: u32 = 3;
    /// Torques that no single force explains, or too few joints to tell.
    pub const NO_SOLUTION: u32 = 4;
}

/// The contact on robot `i` a perception process estimated (`robot/i/contact_estimate`).
pub fn contact_estimate(i: usize) -> Topic<ContactEstimate> {
    Topic::new(&format!("robot/{i}/contact_estimate"))
}
