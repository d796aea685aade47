//! Caravan's physics process as a library: robots described by URDF in a rapier3d world,
//! their joints driven by actuators (the convoy's DC motors and firmware among them), with
//! ground-truth outputs, contacts and applied wrenches. `main.rs` wires it to topics; tests
//! drive it in-process.

pub mod actuator;
pub mod contacts;
pub mod convoy;
pub mod firmware;
pub mod joint_state;
pub mod messages;
pub mod motor;
pub mod params;
pub mod plan;
pub mod scene;
pub mod setup;
pub mod shapes;
pub mod sim;
pub mod spec;
pub mod step_response;
pub mod wrench;

pub use params::Params;
pub use setup::{SetupError, load};
pub use sim::{SimConfig, Simulation};
