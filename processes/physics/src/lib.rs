//! Caravan's physics process as a library: robots described by URDF in a rapier3d world,
//! their joints driven by actuators (the convoy's DC motors and firmware among them), with
//! ground-truth outputs, contacts and applied wrenches. `main.rs` wires it to topics; tests
//! drive it in-process.

pub mod actuator;
pub mod convoy;
pub mod engine_f32;
pub mod engine_f64;
pub mod firmware;
pub mod link_twists;
pub mod messages;
pub mod motor;
pub mod params;
pub mod plan;
pub mod robot;
pub mod setup;
pub mod simulation;
pub mod spec;
pub mod step_response;
pub mod wrench;

pub use params::Params;
pub use robot::SimConfig;
pub use setup::{SetupError, load};
pub use simulation::Simulation;
