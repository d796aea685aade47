//! The engine on rapier's f32 build. The modules under `engine/` are compiled once per
//! precision: each reaches rapier as `super::rapier`, so the same source serves both.
// In the f64 build, rapier's `Real` is f64 and the conversions to f64 are no-ops.
#![allow(clippy::unnecessary_cast)]
// Loading each engine file twice, once per precision, is the point of this module.
#![allow(clippy::duplicate_mod)]

pub use rapier3d as rapier;

#[path = "engine/applied_wrench.rs"]
pub mod applied_wrench;
#[path = "engine/contacts.rs"]
pub mod contacts;
#[path = "engine/joint_state.rs"]
pub mod joint_state;
#[path = "engine/rim.rs"]
pub mod rim;
#[path = "engine/scene.rs"]
pub mod scene;
#[path = "engine/shapes.rs"]
pub mod shapes;
#[path = "engine/sim.rs"]
pub mod sim;
