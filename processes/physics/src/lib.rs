//! Caravan's physics process as a library: the robots of a group in a rapier3d world, driven by
//! DC motors under the reference robot's wheel-speed firmware, with ground-truth outputs and
//! contact events. `main.rs` wires it to topics; tests drive it in-process.

pub mod contacts;
pub mod firmware;
pub mod motor;
pub mod params;
pub mod scene;
pub mod setup;
pub mod sim;
pub mod step_response;

pub use params::Params;
pub use setup::{SetupError, load};
pub use sim::{SimConfig, Simulation};
