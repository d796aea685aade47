//! Leader laser SLAM and follower wheel odometry.
//!
//! - [`slam`]: Hector-style laser SLAM (scan-to-map matching on a multi-resolution
//!   [`grid::OccupancyMap`], [`matcher`]) for the leader, which has a laser and no odometry.
//! - [`odometry`]: dead reckoning from wheel encoder counts for the followers.
//! - [`survey`]: distances measured on a map, to judge the map's scale.
//! - [`map_file`]: maps saved and loaded in the ROS map_server format.
//! - [`synthetic`]: scans of a simple room, for tests and benchmarks.
//!
//! The SLAM follows Hector SLAM (log-odds grids at three resolutions, Gauss–Newton scan-to-map
//! matching, no odometry) except that, by default, scans are matched to a reflection-rate
//! field kept beside the occupancy rather than to the occupancy itself: with the URG's 240°
//! field of view Hector's objective pulls the pose toward the walls in view (see
//! [`matcher`]). The published map is the ordinary occupancy grid.

pub mod grid;
pub mod map_file;
pub mod matcher;
pub mod odometry;
pub mod slam;
pub mod survey;
pub mod synthetic;

pub use grid::OccupancyMap;
pub use matcher::{MatchField, MatchResult, match_scan};
pub use odometry::{OdometryEstimate, WheelOdometry};
pub use slam::{Slam, SlamParams};
pub use survey::surface_distance;
