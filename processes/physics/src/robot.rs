//! What a simulation is built from and reports, the same for either precision of the engine:
//! robots to place, the step configuration, a robot's outputs and contact points.

use crate::actuator::{Actuator, Kinematic};
use crate::params::Precision;
use crate::spec::{JointStart, RobotSpec};
use caravan_world::ObstacleKind;
use caravan_world::description::{JointKind, RobotDescription};
use nalgebra::Isometry3;

/// Everything that shapes the dynamics besides the world and the robots.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimConfig {
    /// Physics step, ns.
    pub dt_ns: u64,
    /// Gravitational acceleration along −z, m/s².
    pub gravity: f64,
    /// Floating-point precision of the engine.
    pub precision: Precision,
    /// rapier's solver iterations per step.
    pub solver_iterations: usize,
}

impl SimConfig {
    pub fn with_dt_ns(dt_ns: u64) -> Self {
        Self {
            dt_ns,
            gravity: 9.81,
            precision: Precision::F32,
            solver_iterations: SOLVER_ITERATIONS,
        }
    }
}

/// Solver iterations (substeps of rapier's soft-TGS solver) per physics step by default (the `solver_iterations` param). With rapier's
/// default of 4 and a 2 ms step, the convoy robot's light wheel (40 g) chatters between its
/// joint and the floor under the 1.4 kg chassis: its speed jitters by 0.06 rad/s rms about
/// the rolling speed. With 8 the jitter is 0.004 rad/s, as with 4 at a 1 ms step, for a
/// third more compute than 4 and two thirds less than halving the step.
pub const SOLVER_ITERATIONS: usize = 8;

/// The topics a robot publishes besides its pose and twist.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Outputs {
    /// `wheel_state` (and `wheel_setpoint` in): the robot is a differential drive.
    pub wheels: bool,
    /// `joint_states` (and `joint_command` in).
    pub joint_states: bool,
    pub link_states: bool,
    pub contacts: bool,
    /// Takes `cmd_vel`: a kinematic base.
    pub cmd_vel: bool,
    /// `force_torque`: the robot has force–torque sensors.
    pub force_torque: bool,
    /// `ground_truth`: base_link's 3-D pose and velocity.
    pub ground_truth: bool,
}

impl Outputs {
    /// What a robot of kind `spec` with description `d` publishes; `diff_drive`: it is a
    /// differential drive.
    pub fn of(spec: &RobotSpec, d: &RobotDescription, diff_drive: bool) -> Self {
        Outputs {
            force_torque: !spec.force_torque.is_empty(),
            ground_truth: spec.ground_truth,
            wheels: diff_drive,
            joint_states: (spec.joint_states).unwrap_or(!d.movable_joints().is_empty()),
            link_states: spec.link_states,
            contacts: spec.contacts,
            cmd_vel: spec.base == crate::spec::Base::Kinematic,
        }
    }

    /// Topics published per step: pose, twist and each output switched on.
    pub fn topic_count(&self) -> usize {
        2 + [
            self.wheels,
            self.joint_states,
            self.link_states,
            self.contacts,
            self.force_torque,
            self.ground_truth,
        ]
        .iter()
        .filter(|on| **on)
        .count()
    }
}

/// A robot to build: its setup and its actuators (one per description joint).
pub struct RobotBuild<'a> {
    pub setup: RobotSetup<'a>,
    pub actuators: Vec<Option<Actuator>>,
    /// Description joint indices of the left and right wheel of a differential drive.
    pub drive: Option<[usize; 2]>,
}

/// A robot to place: its description, its kind's spec and its start pose.
pub struct RobotSetup<'a> {
    pub description: &'a RobotDescription,
    pub spec: &'a RobotSpec,
    pub pose: StartPose,
    /// Inertia added to each joint's child link about the joint axis (an actuator's rotor
    /// seen through its gear), kg·m²; one per joint.
    pub reflected_inertia: Vec<f64>,
    /// Joints moved at exactly their commanded speed, and how ([`Kinematic`]); one per
    /// joint, or empty for none.
    pub kinematic: Vec<Option<Kinematic>>,
    /// Fixed joints that carry a force–torque sensor (description indices), from
    /// [`RobotSpec::sensed_joints`]: not welded.
    pub sensed: Vec<usize>,
    /// Each joint's initial state ([`RobotSpec::initial_joints`]); empty: all at 0, at rest.
    pub initial: Vec<JointStart>,
}

/// Where a robot starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StartPose {
    /// On the floor (a floating base stands on it; a fixed base sits at z = 0).
    Planar { x: f64, y: f64, yaw: f64 },
    /// The base link's full pose.
    Full(Isometry3<f64>),
}

impl RobotSetup<'_> {
    /// The joint axis (in the link frame) and the inertia an actuator adds about it, for
    /// the link a joint moves.
    pub(crate) fn reflected_inertia_of(
        &self,
        link: usize,
    ) -> Option<(nalgebra::Vector3<f64>, f64)> {
        let j = self.description.parent_joint(link)?;
        let joint = &self.description.joints[j];
        let extra = self.reflected_inertia.get(j).copied().unwrap_or(0.0);
        (joint.kind != JointKind::Fixed && extra > 0.0).then_some((joint.axis, extra))
    }

    /// Joint `j`'s initial position (rad or m) and speed (rad/s or m/s): 0 unless given.
    pub(crate) fn start_of(&self, j: usize) -> (f64, f64) {
        let s = self.initial.get(j).copied().unwrap_or_default();
        (s.position.unwrap_or(0.0), s.velocity.unwrap_or(0.0))
    }

    /// Joint `j`'s child frame in its parent body at the joint's initial position: `frame`,
    /// the frame at 0, moved along or turned about the joint's axis.
    pub(crate) fn start_frame(&self, j: usize, frame: &Isometry3<f64>) -> Isometry3<f64> {
        let (q, joint) = (self.start_of(j).0, &self.description.joints[j]);
        let axis = nalgebra::Unit::new_normalize(joint.axis);
        match joint.kind {
            _ if q == 0.0 => *frame,
            JointKind::Prismatic => frame * nalgebra::Translation3::from(axis.into_inner() * q),
            _ => frame * nalgebra::UnitQuaternion::from_axis_angle(&axis, q),
        }
    }

    /// Whether joint `j` is moved kinematically by rapier's kinematic joint.
    pub(crate) fn is_kinematic(&self, j: usize) -> bool {
        self.kinematic.get(j).copied().flatten() == Some(Kinematic::Joint)
    }

    /// Whether joint `j` is a wheel turned as a rim.
    pub(crate) fn is_rim(&self, j: usize) -> bool {
        self.kinematic.get(j).copied().flatten() == Some(Kinematic::Rim)
    }
}

/// Why a start pose cannot be used.
#[derive(Debug, Clone, PartialEq)]
pub enum Overlap {
    /// Robot `robot` overlaps world obstacle `obstacle`.
    Obstacle { robot: usize, obstacle: usize },
    /// Robots `robot` and `other` overlap.
    Robot { robot: usize, other: usize },
}

/// One contact point of a robot's link.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactPoint {
    pub link: usize,
    /// Other robot and its link, or −1, −1 for the world.
    pub other_robot: i32,
    pub other_link: i32,
    /// World frame, m.
    pub point: [f64; 3],
    /// Unit normal pointing from the other body into this link.
    pub normal: [f64; 3],
    /// Normal force over the last step, N.
    pub normal_force: f64,
}

/// "wall", "box" or "cylinder", for messages.
pub fn kind_name(kind: ObstacleKind) -> &'static str {
    match kind {
        ObstacleKind::Wall => "wall",
        ObstacleKind::Box => "box",
        ObstacleKind::Cylinder => "cylinder",
    }
}
