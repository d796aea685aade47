//! The virtual IMU experiment of `shared/reference/imu.md` as a Caravan scenario.
//!
//! A run is a process group: `caravan-physics` (f64, one physics step per node step),
//! `caravan-sensor` with its IMU on the scenario's link, and `caravan-imu-driver`, which
//! moves the body as the scenario says. `caravan-imu-report` then checks every IMU reading
//! against the analytic value of its phase.
//!
//! - [`allan_run`]: the Allan-deviation check of the IMU's error model;
//! - [`arm`]: an IMU on an arm's forearm, off the axis the arm turns about;
//! - [`scenario`]: the scenarios, their commands over time and their analytic readings;
//! - [`range`]: the physical range of every param of the scenarios, checked before start;
//! - [`phase_errors`]: max and RMS error per axis of the readings of each phase;
//! - [`spin_up`]: the spin-up times, analytic and measured, and the reference's table;
//! - [`plot`]: the readings against time, as the reference's figures;
//! - [`report`]: the report plugin's section.

pub mod allan_run;
pub mod arm;
pub mod phase_errors;
pub mod plot;
pub mod range;
pub mod report;
pub mod scenario;
pub mod spin_up;
