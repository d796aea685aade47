//! Applied wrenches as commanded: a force (and a torque) acting at a point on a named link for
//! a while, such as a person's push or a lifting force. The engine's
//! `applied_wrench` module turns a command into forces on a body.

/// A wrench as commanded (`robot/i/wrench`).
#[derive(Debug, Clone, PartialEq)]
pub struct WrenchCommand {
    pub link: String,
    /// Point, force and torque are in the link's frame (else the world's).
    pub in_link_frame: bool,
    /// m.
    pub point: [f64; 3],
    /// N.
    pub force: [f64; 3],
    /// N·m.
    pub torque: [f64; 3],
    /// s; 0: until the next command for the same link.
    pub duration_s: f64,
}
