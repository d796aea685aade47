//! Messages of articulated robots: joint readings and commands, link poses, contact points,
//! and applied wrenches. Joints and links travel by name (at most [`NAME_BYTES`] bytes), as in
//! ROS's `sensor_msgs/JointState`, so that a reader needs no URDF to interpret them.

use crate::describe::Describe;
use crate::{FixedString, FixedVec, Pose3D, Twist, Vector3};
use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};
use serde::Serialize;

/// Longest joint or link name a message carries, bytes (UTF-8).
pub const NAME_BYTES: usize = 60;
/// Most joints in a [`JointState`] or [`JointCommand`].
pub const MAX_JOINTS: usize = 64;
/// Most links in a [`LinkStates`].
pub const MAX_LINKS: usize = 64;
/// Most contact points in a [`Contacts`]; the deepest are kept when there are more.
pub const MAX_CONTACTS: usize = 64;
/// Most force–torque sensors in a [`ForceTorques`].
pub const MAX_FORCE_TORQUE: usize = 16;

/// A joint or link name.
pub type Name = FixedString<NAME_BYTES>;

/// One joint's position, velocity and effort: rad, rad/s, N·m for a revolute or continuous
/// joint; m, m/s, N for a prismatic one.
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::JointValue")]
pub struct JointValue {
    /// The URDF joint's name. In a command, empty means "the joint at this index of
    /// `joint_states`".
    pub name: Name,
    pub position: f64,
    pub velocity: f64,
    pub effort: f64,
}

/// Readings of a robot's movable joints, in URDF order (`robot/i/joint_states`). `effort` is
/// the torque (force) its actuator applied over the last physics step, 0 for a passive joint.
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend, PlacementDefault, Serialize, Describe)]
#[type_name("caravan::JointState")]
pub struct JointState {
    pub joints: FixedVec<JointValue, MAX_JOINTS>,
}

/// Targets for a robot's joint actuators (`robot/i/joint_command`): a position actuator
/// follows `position` (and `velocity` as feed-forward of its damping term, `effort` as
/// feed-forward torque), a velocity actuator `velocity`, an effort actuator `effort`. NaN
/// leaves a field's target as it was; targets are held until changed.
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend, PlacementDefault, Serialize, Describe)]
#[type_name("caravan::JointCommand")]
pub struct JointCommand {
    pub joints: FixedVec<JointValue, MAX_JOINTS>,
}

/// One link's ground-truth pose and velocity in the world frame.
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::LinkState")]
pub struct LinkState {
    pub name: Name,
    /// Pose of the link frame, m and unit quaternion.
    pub pose: Pose3D,
    /// Velocity of the link frame's origin (m/s) and angular velocity (rad/s), world frame.
    pub twist: Twist,
}

impl LinkState {
    pub fn new(name: &str, pose: Pose3D, twist: Twist) -> Self {
        Self {
            name: Name::new(name),
            pose,
            twist,
        }
    }
}

/// Every link of a robot, in URDF order (`robot/i/link_states`), as Gazebo's `LinkStates`.
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend, PlacementDefault, Serialize, Describe)]
#[type_name("caravan::LinkStates")]
pub struct LinkStates {
    pub links: FixedVec<LinkState, MAX_LINKS>,
}

/// A contact point between one of a robot's links and something else.
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::Contact")]
pub struct Contact {
    /// The robot's link.
    pub link: Name,
    /// Index of the other robot, or −1 for the floor or a world obstacle.
    pub other_robot: i32,
    /// The other robot's link; empty for the world.
    pub other_link: Name,
    pub _reserved: u32,
    /// Contact point, world frame, m.
    pub point: Vector3,
    /// Unit normal pointing from the other body into the link.
    pub normal: Vector3,
    /// Normal force over the last physics step, N (≥ 0).
    pub normal_force: f64,
}

impl Contact {
    pub fn new(
        link: &str,
        other_robot: i32,
        other_link: &str,
        point: Vector3,
        normal: Vector3,
        normal_force: f64,
    ) -> Self {
        Self {
            link: Name::new(link),
            other_robot,
            other_link: Name::new(other_link),
            _reserved: 0,
            point,
            normal,
            normal_force,
        }
    }
}

/// A robot's contact points after the last step (`robot/i/contacts`).
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend, PlacementDefault, Serialize, Describe)]
#[type_name("caravan::Contacts")]
pub struct Contacts {
    pub contacts: FixedVec<Contact, MAX_CONTACTS>,
}

/// A force (and torque) applied at a point on a named link for a while
/// (`robot/i/wrench`): a person's push, a lifting force. A new wrench on a link replaces the
/// one acting on it; a zero wrench ends it.
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::Wrench")]
pub struct Wrench {
    pub link: Name,
    /// [`Wrench::WORLD`]: point, force and torque in the world frame; [`Wrench::LINK`]: in
    /// the link's frame (the force then turns with the link).
    pub frame: u32,
    pub _reserved: u32,
    /// Application point, m.
    pub point: Vector3,
    /// N.
    pub force: Vector3,
    /// N·m.
    pub torque: Vector3,
    /// How long it acts, s; 0 until the next wrench on the same link.
    pub duration_s: f64,
}

impl Wrench {
    pub const WORLD: u32 = 0;
    pub const LINK: u32 = 1;
}

/// A force–torque sensor's reading: what the parent exerts on the child through a fixed
/// joint, in the child link's frame, as Gazebo's ForceTorque sensor (child, child-to-parent).
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::ForceTorque")]
pub struct ForceTorque {
    /// The fixed joint that carries the sensor.
    pub joint: Name,
    /// N.
    pub force: Vector3,
    /// About the child link's origin, N·m.
    pub torque: Vector3,
}

/// A robot's force–torque sensors after the last step (`robot/i/force_torque`).
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend, PlacementDefault, Serialize, Describe)]
#[type_name("caravan::ForceTorques")]
pub struct ForceTorques {
    pub sensors: FixedVec<ForceTorque, MAX_FORCE_TORQUE>,
}

impl JointState {
    /// The reading of the joint named `name`.
    pub fn get(&self, name: &str) -> Option<&JointValue> {
        self.joints
            .as_slice()
            .iter()
            .find(|j| j.name.as_str() == name)
    }
}

impl LinkStates {
    /// The state of the link named `name`.
    pub fn get(&self, name: &str) -> Option<&LinkState> {
        self.links
            .as_slice()
            .iter()
            .find(|l| l.name.as_str() == name)
    }
}
