use crate::describe::Describe;
use crate::{Quaternion, Vector3};
use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};
use serde::Serialize;

/// Largest number of beams a [`LaserScan`] holds (a 270° scanner at 0.25°).
pub const SCAN_MAX_BEAMS: usize = 1081;

/// A planar laser scan, with the fields of sensor_msgs/LaserScan.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Describe)]
#[type_name("caravan::LaserScan")]
pub struct LaserScan {
    /// Start and end angle of the scan, rad.
    pub angle_min: f32,
    pub angle_max: f32,
    /// Angle between beams, rad.
    pub angle_increment: f32,
    /// Time between beams, s.
    pub time_increment: f32,
    /// Time between scans, s.
    pub scan_time: f32,
    /// Valid range interval, m; readings outside it are invalid.
    pub range_min: f32,
    pub range_max: f32,
    /// Number of valid entries in `ranges` and `intensities`.
    pub beam_count: u32,
    #[count(beam_count)]
    pub ranges: [f32; SCAN_MAX_BEAMS],
    #[count(beam_count)]
    pub intensities: [f32; SCAN_MAX_BEAMS],
}

impl Default for LaserScan {
    fn default() -> Self {
        crate::placement_new()
    }
}

impl LaserScan {
    pub fn ranges(&self) -> &[f32] {
        &self.ranges[..(self.beam_count as usize).min(SCAN_MAX_BEAMS)]
    }
}

/// Inertial measurement, as sensor_msgs/Imu.
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::Imu")]
pub struct Imu {
    pub orientation: Quaternion,
    /// Row-major 3×3; element 0 = −1 means "orientation not estimated".
    pub orientation_covariance: [f64; 9],
    /// rad/s
    pub angular_velocity: Vector3,
    pub angular_velocity_covariance: [f64; 9],
    /// m/s², including gravity
    pub linear_acceleration: Vector3,
    pub linear_acceleration_covariance: [f64; 9],
}
