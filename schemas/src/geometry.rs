use crate::describe::Describe;
use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};
use serde::Serialize;

/// A pose in the plane: metres and radians, REP 103 (x forward, y left, θ counter-clockwise).
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::Pose2D")]
pub struct Pose2D {
    pub x: f64,
    pub y: f64,
    pub theta: f64,
}

#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::Vector3")]
pub struct Vector3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

/// A unit quaternion (x, y, z, w) as in geometry_msgs/Quaternion.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe)]
#[type_name("caravan::Quaternion")]
pub struct Quaternion {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Self {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }
    }
}

impl Quaternion {
    /// Rotation by `yaw` about z.
    pub fn from_yaw(yaw: f64) -> Self {
        let (s, c) = (yaw / 2.0).sin_cos();
        Self {
            x: 0.0,
            y: 0.0,
            z: s,
            w: c,
        }
    }

    /// Yaw (rotation about z) of this orientation.
    pub fn yaw(&self) -> f64 {
        (2.0 * (self.w * self.z + self.x * self.y))
            .atan2(1.0 - 2.0 * (self.y * self.y + self.z * self.z))
    }
}

/// An angle brought into (−π, π], rad: the one wrap every process uses for headings.
pub fn wrap_angle(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let w = a.rem_euclid(TAU);
    if w > PI { w - TAU } else { w }
}

/// A pose in space, as geometry_msgs/Pose.
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::Pose3D")]
pub struct Pose3D {
    pub position: Vector3,
    pub orientation: Quaternion,
}

/// Linear and angular velocity, as geometry_msgs/Twist (m/s, rad/s).
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::Twist")]
pub struct Twist {
    pub linear: Vector3,
    pub angular: Vector3,
}

impl Twist {
    /// A ground robot's velocity: `v` forward along x, turning at `omega` about z.
    pub fn planar(v: f64, omega: f64) -> Self {
        Self {
            linear: Vector3 {
                x: v,
                y: 0.0,
                z: 0.0,
            },
            angular: Vector3 {
                x: 0.0,
                y: 0.0,
                z: omega,
            },
        }
    }
}
