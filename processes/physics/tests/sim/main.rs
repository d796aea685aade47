//! In-process tests of the physics: the simulation is driven directly, without iceoryx2.
//! Every time is simulated time.

mod articulated;
mod bad_input;
mod collisions;
mod common;
mod determinism;
mod driving;
mod force_torque;
mod initial;
mod lab;
mod link_twists;
mod params;
mod precision;
mod step_response;
mod tracks;
