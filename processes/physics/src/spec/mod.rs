//! One kind of robot in the physics params: its URDF, how many, where, how its base is held,
//! which joint solver it uses and which actuators drive its joints.
//!
//! ```toml
//! robots = [
//!   { urdf = "robots/arm.urdf", base = "fixed", poses = [[0.0, 0.0, 0.0]],
//!     actuators = [{ type = "position", joints = ["*"], kp = 200.0, kd = 5.0 }],
//!     link_states = true, contacts = true },
//!   { urdf = "robots/drone.urdf", base = "kinematic", count = 2 },
//! ]
//! ```

mod actuator;
mod assign;
mod initial;

pub use actuator::ActuatorSpec;
pub use initial::JointStart;

use crate::firmware::FirmwareParams;
use crate::motor::MotorParams;
use serde::Deserialize;
use std::collections::BTreeMap;

/// How a robot's root link is held.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, serde::Serialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Base {
    /// A free body under gravity and contacts (a wheeled robot, a thrown box).
    #[default]
    Floating,
    /// Bolted to the world at its start pose (an arm on a table).
    Fixed,
    /// Moved at commanded velocities (`robot/i/cmd_vel`), pushed by nothing (a drone flown
    /// by its autopilot, no aerodynamics).
    Kinematic,
}

/// How joints are solved.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, serde::Serialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum JointModel {
    /// Multibody for a fixed base, impulse joints otherwise.
    #[default]
    Auto,
    /// Reduced coordinates (rapier multibody): joints hold exactly, link poses and joint
    /// torques carry no constraint drift. Right for arms.
    Multibody,
    /// Bodies in maximal coordinates held by impulse constraints: the convoy's wheels, whose
    /// motor constants were fitted this way.
    Impulse,
}

/// A frame of velocity commands for a kinematic base.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, serde::Serialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum CmdVelFrame {
    /// Velocities in the base link's frame, as ROS `cmd_vel`.
    #[default]
    Body,
    /// Velocities in the world (map) frame.
    World,
}

/// One kind of robot and its instances.
#[derive(Debug, Clone, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    /// Robot description (URDF), relative to the launch file's directory.
    pub urdf: String,
    /// Number of robots of this kind (default 1).
    #[serde(default = "one")]
    pub count: usize,
    /// Start pose of each robot of this kind, base link in the map frame: `[x, y, yaw]` (m, m,
    /// rad; a floating base then stands on the floor, on its wheels if it has any, else on its
    /// lowest point; a fixed one sits at z = 0) or `[x, y, z, roll, pitch, yaw]`. Empty: the
    /// world file's `[[start]]` poses, in robot order.
    #[serde(default)]
    pub poses: Vec<Vec<f64>>,
    /// How the robot's root link is held.
    #[serde(default)]
    pub base: Base,
    /// Hold the base fixed 0.1 m above its standing height so wheels spin freely (the
    /// motor bench test).
    #[serde(default)]
    pub lifted: bool,
    /// The joint solver (docs/robots.md).
    #[serde(default)]
    pub joints: JointModel,
    /// The actuators and the joints they drive, each entry naming `joints` (names or `"*"`); a
    /// later entry overrides an earlier one for the same joint. None: every joint passive. See
    /// docs/robots.md.
    #[serde(default)]
    pub actuators: Vec<ActuatorSpec>,
    /// `"diff"`: the robot is a differential drive; its two wheel joints follow
    /// `robot/i/wheel_setpoint` and report on `robot/i/wheel_state`.
    #[serde(default)]
    pub drive: Option<Drive>,
    /// Tyre–floor friction coefficient of the wheels (cylinders on continuous joints).
    #[serde(default = "default_wheel_friction")]
    pub wheel_friction: f64,
    /// Frame of `robot/i/cmd_vel` for a kinematic base (`base = "kinematic"`).
    #[serde(default)]
    pub cmd_vel_frame: CmdVelFrame,
    /// Publish `robot/i/joint_states` and take `robot/i/joint_command`. Default: when the
    /// robot has a movable joint.
    #[serde(default)]
    pub joint_states: Option<bool>,
    /// Fixed joints that carry a force–torque sensor: their child is not welded to the parent
    /// but held by a fixed (impulse) joint whose constraint force and torque are published on
    /// `robot/i/force_torque`. A moving or missing joint is refused.
    #[serde(default)]
    pub force_torque: Vec<String>,
    /// rapier's joint softness for the `force_torque` joints (needs `force_torque`). Default:
    /// rigid (rapier's joint defaults). Soft, the joint is solved as ODE's and Bullet's soft
    /// constraints (ERP/CFM) solve every joint, and the force read lags each change of load (10
    /// Hz, 0.3: 63 % after about 20 ms).
    #[serde(default)]
    pub force_torque_softness: Option<Softness>,
    /// Let the robot's links touch each other (those not joined by a joint). Default: no,
    /// as Gazebo's `<self_collide>`; rows of overlapping wheels need it off.
    #[serde(default)]
    pub self_collide: bool,
    /// Publish `robot/i/ground_truth` (base_link's 3-D pose and velocity, map frame).
    #[serde(default)]
    pub ground_truth: bool,
    /// Publish `robot/i/link_states` (every link's pose and velocity).
    #[serde(default)]
    pub link_states: bool,
    /// Publish `robot/i/contacts` (contact points and normal forces).
    #[serde(default)]
    pub contacts: bool,
    /// Joint positions at the start, by joint name (MoveIt's `initial_positions`): rad
    /// (revolute, continuous) or m (prismatic), finite, within the joint's URDF `<limit
    /// lower upper>`. Joints left out start at 0, the URDF's pose. The bodies are placed there
    /// before the first step, and an actuator holding a position (`position`, `servo`) starts
    /// with it as its target.
    #[serde(default)]
    pub initial_positions: BTreeMap<String, f64>,
    /// Joint velocities at the start, by joint name: rad/s (revolute, continuous) or m/s
    /// (prismatic), finite, |v| ≤ the joint's URDF `<limit velocity>`. Joints left out start
    /// at rest. An actuator following a velocity (`velocity`, `motor`, `kinematic`, `rim`,
    /// `dc_motor`) starts with it as its target.
    #[serde(default)]
    pub initial_velocities: BTreeMap<String, f64>,
}

/// rapier's softness of a joint's locked axes (its constraint regularisation, the
/// counterpart of ODE's ERP and CFM), not a physical spring: on a 1 kg test mass at 10 Hz and
/// 0.3, a step of load reaches 63 % of its final reading after about 20 ms and does not
/// overshoot.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Softness {
    /// rapier's natural frequency, Hz, > 0 (its rigid default is 1e6).
    pub natural_frequency_hz: f64,
    /// rapier's damping ratio, > 0 (its rigid default is 1).
    pub damping_ratio: f64,
}

#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Deserialize, serde::Serialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Drive {
    Diff,
}

fn one() -> usize {
    1
}
fn default_wheel_friction() -> f64 {
    1.0
}

impl RobotSpec {
    /// The joint solver this robot gets.
    pub fn joint_model(&self) -> JointModel {
        match (self.joints, self.base) {
            (JointModel::Auto, Base::Fixed) => JointModel::Multibody,
            (JointModel::Auto, _) => JointModel::Impulse,
            (m, _) => m,
        }
    }

    /// Checks values serde cannot; messages name the key relative to this spec (see also
    /// [`check_pose_values`] and [`check_wheel_friction`], shared with the convoy's keys).
    pub fn validate(&self) -> Result<(), String> {
        if self.count == 0 {
            return Err("'count' must be at least 1".into());
        }
        if !self.poses.is_empty() && self.poses.len() != self.count {
            return Err(format!(
                "'poses': {} start pose(s) for count = {}; give one per robot, or none to \
                 use the world file's [[start]] poses",
                self.poses.len(),
                self.count
            ));
        }
        for (i, p) in self.poses.iter().enumerate() {
            if p.len() != 3 && p.len() != 6 {
                return Err(format!(
                    "'poses[{i}]': give [x, y, yaw] or [x, y, z, roll, pitch, yaw], got {} \
                     numbers",
                    p.len()
                ));
            }
            check_pose_values(i, p)?;
        }
        check_wheel_friction(self.wheel_friction)?;
        if self.lifted && self.base != Base::Floating {
            return Err(
                "'lifted' holds a floating base in the air; this base is not floating".into(),
            );
        }
        for (k, a) in self.actuators.iter().enumerate() {
            a.validate().map_err(|e| format!("'actuators[{k}]': {e}"))?;
        }
        self.check_initial_values()?;
        if let Some(m) = self.force_torque_softness {
            for (key, v) in [
                ("natural_frequency_hz", m.natural_frequency_hz),
                ("damping_ratio", m.damping_ratio),
            ] {
                if !(v.is_finite() && v > 0.0) {
                    return Err(format!(
                        "'force_torque_softness.{key}': must be a positive number, got {v}"
                    ));
                }
            }
            if self.force_torque.is_empty() {
                return Err(
                    "'force_torque_softness' is set but 'force_torque' names no joint".into(),
                );
            }
        }
        Ok(())
    }
}

impl RobotSpec {
    /// A floating differential drive on impulse joints (what the DC motor was fitted with)
    /// whose every movable joint is a `dc_motor`, without `joint_states`: the `robots` entry
    /// the params' top-level one-kind form stands for, and the convoy robot's.
    pub fn dc_motor_diff_drive(
        urdf: &str,
        count: usize,
        poses: &[[f64; 3]],
        lifted: bool,
        wheel_friction: f64,
        motor: MotorParams,
        pid: FirmwareParams,
    ) -> Self {
        RobotSpec {
            urdf: urdf.to_string(),
            count,
            poses: poses.iter().map(|p| p.to_vec()).collect(),
            base: Base::Floating,
            lifted,
            joints: JointModel::Impulse,
            actuators: vec![ActuatorSpec::DcMotor {
                joints: vec!["*".into()],
                motor,
                pid,
            }],
            drive: Some(Drive::Diff),
            wheel_friction,
            cmd_vel_frame: CmdVelFrame::Body,
            joint_states: Some(false),
            force_torque: Vec::new(),
            force_torque_softness: None,
            self_collide: false,
            ground_truth: false,
            link_states: false,
            contacts: false,
            initial_positions: BTreeMap::new(),
            initial_velocities: BTreeMap::new(),
        }
    }
}

/// A start pose's numbers: finite and within a world (caravan-world's limit, which also bounds
/// the angles well past any turn).
pub fn check_pose_values(i: usize, pose: &[f64]) -> Result<(), String> {
    use caravan_world::limits::{MAX_WORLD_EXTENT_M, coordinate};
    for (k, v) in pose.iter().enumerate() {
        coordinate(&format!("'poses[{i}][{k}]'"), *v, MAX_WORLD_EXTENT_M)?;
    }
    Ok(())
}

/// The wheels' friction coefficient: positive and at most 100.
pub fn check_wheel_friction(v: f64) -> Result<(), String> {
    if !(v > 0.0 && v <= 100.0) {
        return Err(format!(
            "'wheel_friction': must be positive and at most 100, got {v}"
        ));
    }
    Ok(())
}
