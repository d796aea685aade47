//! Contact force and contact point identification on a planar arm from its joint torques,
//! after `shared/reference/contact-identification.md`, as a Caravan scenario.
//!
//! - [`arm_urdf`]: the arm as a URDF, generated and read back;
//! - [`arm_dynamics`]: the arm's own joint torques M(q)·q̈ + C(q, q̇)·q̇, for the dynamic
//!   estimator;
//! - [`contour`]: a link's surface, a convex contour of 16 segments;
//! - [`planar_arm`]: the arm's geometry, kinematics and the torques of a push;
//! - [`identify`]: the analytical identification (extended wrench, line of action, entry
//!   point in the friction cone, candidate links, depth fall-back);
//! - [`depth`]: the sparse depth sensor and its self-filter;
//! - [`joints`]: the arm's joint angles and torques out of a joint-state message;
//! - [`live`]: a live run's estimates scored against the pushes applied;
//! - [`monte_carlo`]: the reference's Table 1 by Monte-Carlo, timed against the optimiser;
//! - [`optimiser`]: the baseline, the same problem solved by a constrained optimiser;
//! - [`report`]: the report plugin's `contact` section;
//! - [`scenario`]: the params the scenario's processes share;
//! - [`table`]: the Monte-Carlo trials summarised beside the reference's table;
//! - [`plot`]: the live run's plot;
//! - [`push`]: random poses and pushes, for the Monte-Carlo and the scripted person;
//! - [`range`]: the physical range of every param, checked before the group starts;

pub mod arm_dynamics;
pub mod arm_urdf;
pub mod contour;
pub mod depth;
pub mod identify;
pub mod joints;
pub mod live;
pub mod messages;
pub mod monte_carlo;
pub mod optimiser;
pub mod planar_arm;
pub mod plot;
pub mod push;
pub mod range;
pub mod report;
pub mod scenario;
pub mod table;
