//! The tracked rescue robot of `shared/reference/tracked-robot.md` as a Caravan scenario:
//! tracks made of rows of (gear) wheels, a differential drive, box steps (the Random Step
//! Environment terrain is in progress).
//!
//! - [`crossing`]: a crossing's outcome (passed, stuck, flipped) from the true pose;
//! - [`diff_drive`]: the drive controller's limits, wheel speeds and wheel odometry;
//! - [`report`]: the `tracked` report section;
//! - [`running_gear`]: the wheels of the four running-gear variants;
//! - [`urdf`]: a variant's robot description;

pub mod crossing;
pub mod diff_drive;
pub mod report;
pub mod running_gear;
pub mod urdf;
