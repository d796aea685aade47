use crate::describe::Describe;
use crate::{FixedVec, Pose2D, Pose3D, Twist};
use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};
use serde::Serialize;

/// Wheel-speed set-points for the motor controller, in rad/s.
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::WheelSetpoint")]
pub struct WheelSetpoint {
    pub left_rad_s: f64,
    pub right_rad_s: f64,
}

/// Measured state of the two driven wheels.
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::WheelState")]
pub struct WheelState {
    /// Accumulated wheel angle, rad.
    pub left_angle_rad: f64,
    pub right_angle_rad: f64,
    /// Wheel speed, rad/s.
    pub left_rad_s: f64,
    pub right_rad_s: f64,
    /// Motor voltage applied by the firmware, V.
    pub left_voltage: f64,
    pub right_voltage: f64,
}

/// Accumulated encoder counts of the two driven wheels.
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, Eq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::EncoderTicks")]
pub struct EncoderTicks {
    pub left: i64,
    pub right: i64,
    /// Encoder resolution, ticks per wheel revolution.
    pub ticks_per_rev: u32,
    pub _reserved: u32,
}

/// Pose and twist estimate with covariances, as nav_msgs/Odometry.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe)]
#[type_name("caravan::Odometry")]
pub struct Odometry {
    pub pose: Pose3D,
    /// Row-major 6×6 covariance of (x, y, z, roll, pitch, yaw).
    #[serde(serialize_with = "crate::json::slice")]
    pub pose_covariance: [f64; 36],
    /// Twist in the robot frame.
    pub twist: Twist,
    #[serde(serialize_with = "crate::json::slice")]
    pub twist_covariance: [f64; 36],
}

impl Default for Odometry {
    fn default() -> Self {
        crate::placement_new()
    }
}

/// A contact between a robot and another robot or an obstacle began or ended.
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, Eq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::Collision")]
pub struct Collision {
    /// Index of the robot.
    pub robot: u32,
    /// Index of the other robot, or −1 for a world obstacle (wall, box, cylinder).
    pub other_robot: i32,
    /// 1 when the contact began, 0 when it ended.
    pub started: u32,
    pub _reserved: u32,
}

/// Most robots a [`RobotStates`] message holds.
pub const MAX_ROBOT_STATES: usize = 128;

/// One robot's ground truth in [`RobotStates`]: what its `robot/i/pose_true` and
/// `robot/i/twist_true` carry.
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::RobotState")]
pub struct RobotState {
    /// base_link in the map frame: x, y in m, heading in rad.
    pub pose: Pose2D,
    /// base_link origin's linear velocity (m/s) and the angular velocity (rad/s), both in the
    /// map frame.
    pub twist: Twist,
}

/// Every robot's ground truth after a physics step, robot `i` at index `i`
/// (`robots/state_true`): one message for the whole team where the per-robot topics take two
/// per robot, as Gazebo's `model_states` beside each model's own topics. The physics sends
/// it only while someone reads it, and only for up to [`MAX_ROBOT_STATES`] robots.
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend, PlacementDefault, Serialize, Describe)]
#[type_name("caravan::RobotStates")]
pub struct RobotStates {
    pub robots: FixedVec<RobotState, MAX_ROBOT_STATES>,
}

impl Default for RobotStates {
    fn default() -> Self {
        crate::placement_new()
    }
}
