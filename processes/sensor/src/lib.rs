//! Caravan's per-robot sensors, one process per robot as on its Raspberry Pi:
//! - [`laser`]: a planar laser scanner (Hokuyo URG-04LX-UG01 defaults) by ray casting;
//! - [`encoders`]: wheel encoder ticks from the wheels' accumulated angles;
//! - [`imu`]: a virtual accelerometer, gyroscope and orientation from ground truth;
//! - [`suite`]: one robot's sensors step by step, between the node's inputs and outputs.
//!
//! The algorithms live here with their tests; `main.rs` only wires them to topics.

pub mod allan;
pub mod attach;
pub mod encoders;
pub mod force_accel;
pub mod imu;
pub mod imu_errors;
pub mod laser;
pub mod noise;
pub mod params;
pub mod schedule;
pub mod suite;
pub mod sync;
