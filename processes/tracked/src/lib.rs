//! The tracked rescue robot of `shared/reference/tracked-robot.md` as a Caravan scenario:
//! tracks made of rows of (gear) wheels, driven across Random Step Environment terrain.
//!
//! - [`braking`]: the braking distance after the operator's stop;
//! - [`climb`]: the operator's flipper sequence for climbing a step;
//! - [`crossing`]: a crossing's outcome (passed, stuck, flipped, off the world) from the true pose;
//! - [`diff_drive`]: the drive controller's limits, wheel speeds and wheel odometry;
//! - [`keep_line`]: the operator's steering back to the line it started on;
//! - [`flippers`]: the flipper command topic and the drive's speed-limited flipper targets;
//! - [`params`]: checks shared by the processes' params;
//! - [`passability`]: a sweep's crossings pooled into the passability table;
//! - [`report`]: the `tracked` report section;
//! - [`resting`]: what a robot rests on at the end (the chassis' share of its contact force);
//! - [`running_gear`]: the wheels of the four running-gear variants;
//! - [`urdf`]: a variant's robot description;
//! - [`rse`]: the Random Step Environment generator (blocks, primitives, softness);
//! - [`rse_check`]: a terrain spec's keys checked against their ranges, named with their line;
//! - [`rse_world`]: a terrain as a world file of boxes, and its picture.

pub mod braking;
pub mod climb;
pub mod crossing;
pub mod diff_drive;
pub mod flippers;
pub mod keep_line;
pub mod params;
pub mod passability;
pub mod report;
pub mod resting;
pub mod rse;
pub mod rse_check;
pub mod rse_world;
pub mod running_gear;
pub mod urdf;
