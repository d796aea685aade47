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

use crate::firmware::FirmwareParams;
use crate::motor::MotorParams;
use caravan_world::description::{JointKind, RobotDescription};
use serde::Deserialize;

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

/// An actuator model and the joints it drives. `joints = ["*"]` means every movable joint;
/// later entries override earlier ones for the same joint. Torques are bounded by the URDF's
/// `<limit effort>`, speed targets by `<limit velocity>`, position targets by the joint's
/// position limits.
#[derive(Debug, Clone, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ActuatorSpec {
    /// A DC gear motor ([`crate::motor`]) under a wheel-speed firmware (an incremental PID
    /// at `pid.rate_hz`, [`crate::firmware`]); takes velocity targets. The keys left out keep
    /// the measured motor and firmware of the convoy robot ([`crate::step_response`]).
    DcMotor {
        /// The joints it drives, by name, or `["*"]` for every movable joint.
        joints: Vec<String>,
        #[serde(default)]
        motor: MotorParams,
        #[serde(default)]
        pid: FirmwareParams,
    },
    /// A speed loop: τ = kp·(ω* − ω) + ki·∫(ω* − ω)dt, every physics step.
    Velocity {
        /// The joints it drives, by name, or `["*"]` for every movable joint.
        joints: Vec<String>,
        /// N·m·s/rad (N·s/m for prismatic joints), ≥ 0.
        #[serde(default = "default_velocity_kp")]
        kp: f64,
        /// N·m/rad (N/m), ≥ 0.
        #[serde(default)]
        ki: f64,
    },
    /// A position loop as ros2_control's effort-interface PID:
    /// τ = kp·e + ki·∫e dt + kd·(ω* − ω) + τ_ff, every physics step.
    Position {
        /// The joints it drives, by name, or `["*"]` for every movable joint.
        joints: Vec<String>,
        /// N·m/rad (N/m), ≥ 0.
        #[serde(default = "default_position_kp")]
        kp: f64,
        /// N·m/(rad·s) (N/(m·s)), ≥ 0.
        #[serde(default)]
        ki: f64,
        /// N·m·s/rad (N·s/m), ≥ 0.
        #[serde(default = "default_position_kd")]
        kd: f64,
    },
    /// rapier's velocity motor on the joint, solved with the contacts (implicitly, as
    /// Gazebo's velocity-controlled joints under ODE): it holds the target speed with at most
    /// the URDF's effort, stable at any step for however light the link. Takes velocity
    /// targets. Its `effort` reads 0 on multibody joints: rapier does not report the impulses
    /// of a multibody's internal constraints.
    Motor {
        /// The joints it drives, by name, or `["*"]` for every movable joint.
        joints: Vec<String>,
        /// rapier's motor damping (acceleration-based), 1/s, > 0: how hard the speed error
        /// is corrected; large is stiff.
        #[serde(default = "default_motor_damping")]
        damping: f64,
    },
    /// A position servo: it pulls the joint to its position target (never commanded: the
    /// URDF's zero) as a spring of `stiffness` and a damper of `damping` on the speed error
    /// (the velocity target is its feed-forward, default 0), the spring with at most the
    /// URDF's effort. Stable at any step for however light the link (a flipper carrying
    /// wheels, a gripper's finger). Takes position (and velocity) targets; an infinite
    /// position clears the target back to 0. On impulse joints it is rapier's motor, solved
    /// with the contacts; on multibody joints rapier's implicit joint spring and damper (the
    /// damper unbounded), which reads its effort.
    Servo {
        /// The joints it drives, by name, or `["*"]` for every movable joint.
        joints: Vec<String>,
        /// N·m/rad (N/m), > 0.
        #[serde(default = "default_servo_stiffness")]
        stiffness: f64,
        /// N·m·s/rad (N·s/m), ≥ 0.
        #[serde(default = "default_servo_damping")]
        damping: f64,
    },
    /// The joint moves exactly as commanded, whatever the load: an ideal velocity source
    /// (Gazebo's `JointVelocityCmd`), for joints whose motors never saturate. A velocity
    /// target is held as given; a position target is reached at up to the URDF's velocity
    /// limit and held (never commanded: stand still). Targets are clamped to the URDF's
    /// limits. rapier's kinematic multibody joint: the joint leaves the dynamics, so the
    /// multibody's mass matrix to solve shrinks by one row per joint (a tracked robot's
    /// 36 wheels: 44 rows to 8). Multibody robots only, and rapier 0.36 then solves no joint
    /// limits or motors in that multibody: no joint may take a `motor`, and joint limits
    /// are held only by the clamped targets of kinematic and `servo` joints, so every other
    /// joint with limits (revolute, prismatic) is refused. Its `effort` reads 0.
    Kinematic { joints: Vec<String> },
    /// A wheel (continuous joint) turned exactly as commanded, like `kinematic`, without
    /// the joint's degree of freedom: the wheel is welded to its parent, the weld's frame
    /// turns at the commanded speed, and each of its contacts is given the speed of the
    /// wheel's surface at that point (rapier's contact `tangent_velocity`, and its motion
    /// along the normal as a change of the contact's distance over the step). To the
    /// contacts that is the kinematic joint; the multibody's mass matrix, which rapier
    /// assembles densely over every link, keeps only the robot's other joints (a tracked
    /// robot's 36 wheels: 8 rows instead of 44, and no work for the 36 links' columns).
    /// Multibody robots only (on impulse joints the weld's turning frame would spin the
    /// wheel's body as well), beside any other actuator. Its `effort` reads 0.
    Rim { joints: Vec<String> },
    /// The commanded effort, bounded by the URDF's.
    Effort { joints: Vec<String> },
    /// A passive joint: no actuator (the default for every joint).
    None { joints: Vec<String> },
}

fn default_motor_damping() -> f64 {
    1000.0
}
fn default_velocity_kp() -> f64 {
    1.0
}
fn default_servo_stiffness() -> f64 {
    1000.0
}
fn default_servo_damping() -> f64 {
    50.0
}
fn default_position_kp() -> f64 {
    100.0
}
fn default_position_kd() -> f64 {
    2.0
}

impl ActuatorSpec {
    pub fn joints(&self) -> &[String] {
        match self {
            ActuatorSpec::DcMotor { joints, .. }
            | ActuatorSpec::Velocity { joints, .. }
            | ActuatorSpec::Motor { joints, .. }
            | ActuatorSpec::Servo { joints, .. }
            | ActuatorSpec::Position { joints, .. }
            | ActuatorSpec::Kinematic { joints }
            | ActuatorSpec::Rim { joints }
            | ActuatorSpec::Effort { joints }
            | ActuatorSpec::None { joints } => joints,
        }
    }

    fn validate(&self) -> Result<(), String> {
        let gains: &[(&str, f64)] = match self {
            ActuatorSpec::DcMotor { motor, pid, .. } => {
                motor.validate()?;
                return pid.validate();
            }
            ActuatorSpec::Velocity { kp, ki, .. } => &[("kp", *kp), ("ki", *ki)],
            ActuatorSpec::Motor { damping, .. } => {
                if !(damping.is_finite() && *damping > 0.0) {
                    return Err(format!("damping must be positive, got {damping}"));
                }
                &[]
            }
            ActuatorSpec::Servo {
                stiffness, damping, ..
            } => {
                if !(stiffness.is_finite() && *stiffness > 0.0) {
                    return Err(format!("stiffness must be positive, got {stiffness}"));
                }
                &[("damping", *damping)]
            }
            ActuatorSpec::Position { kp, ki, kd, .. } => &[("kp", *kp), ("ki", *ki), ("kd", *kd)],
            ActuatorSpec::Kinematic { .. }
            | ActuatorSpec::Rim { .. }
            | ActuatorSpec::Effort { .. }
            | ActuatorSpec::None { .. } => &[],
        };
        for (key, v) in gains {
            if !(v.is_finite() && *v >= 0.0) {
                return Err(format!("{key} must be zero or positive, got {v}"));
            }
        }
        Ok(())
    }
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

    /// The actuator of each joint of `d` (`None`: passive), after checking that every named
    /// joint exists and moves.
    pub fn assign<'a>(
        &'a self,
        d: &RobotDescription,
    ) -> Result<Vec<Option<&'a ActuatorSpec>>, String> {
        // The entry that last named each joint, `none` entries included.
        let mut entry = vec![None; d.joints.len()];
        for (k, a) in self.actuators.iter().enumerate() {
            if a.joints().is_empty() {
                return Err(format!("'actuators[{k}].joints' is empty"));
            }
            for name in a.joints() {
                let chosen: Vec<usize> = if name == "*" {
                    d.movable_joints()
                } else {
                    let j = d.joint(name).ok_or_else(|| {
                        format!(
                            "'actuators[{k}].joints': no joint named '{name}' in {} (joints: {})",
                            d.file,
                            names(d)
                        )
                    })?;
                    if d.joints[j].kind == JointKind::Fixed {
                        return Err(format!(
                            "'actuators[{k}].joints': joint '{name}' of {} is fixed; an \
                             actuator needs a revolute, continuous or prismatic joint",
                            d.file
                        ));
                    }
                    vec![j]
                };
                for j in chosen {
                    entry[j] = Some(k);
                }
            }
        }
        self.check_kinematic(d, &entry)?;
        self.check_rims(d, &entry)?;
        Ok(entry
            .iter()
            .map(|k| match &self.actuators[(*k)?] {
                ActuatorSpec::None { .. } => None,
                a => Some(a),
            })
            .collect())
    }

    /// A rim is a wheel's, in a multibody: only continuous joints turn that way.
    fn check_rims(&self, d: &RobotDescription, entry: &[Option<usize>]) -> Result<(), String> {
        for (j, &k) in entry.iter().enumerate() {
            let Some(k) = k else { continue };
            let rim = matches!(self.actuators[k], ActuatorSpec::Rim { .. });
            if rim && self.joint_model() != JointModel::Multibody {
                return Err(format!(
                    "'actuators[{k}]': a rim needs joints = \"multibody\" (on impulse joints \
                     the weld's turning frame would also spin the wheel's own body)"
                ));
            }
            if rim && d.joints[j].kind != JointKind::Continuous {
                return Err(format!(
                    "'actuators[{k}]': joint '{}' of {} is not continuous; a rim turns wheels \
                     (continuous joints) only",
                    d.joints[j].name, d.file
                ));
            }
        }
        Ok(())
    }

    /// A multibody with kinematic joints: rapier 0.36 builds its limit and motor constraints
    /// against the full mass matrix while the kinematic joints have left it (it panics), so
    /// no joint may take a motor, and every limited joint must hold its limits by clamped
    /// targets (kinematic or servo).
    fn check_kinematic(&self, d: &RobotDescription, entry: &[Option<usize>]) -> Result<(), String> {
        let spec = |k: Option<usize>| k.map(|k| &self.actuators[k]);
        let Some(k) = entry
            .iter()
            .flatten()
            .copied()
            .find(|&k| matches!(self.actuators[k], ActuatorSpec::Kinematic { .. }))
        else {
            return Ok(());
        };
        if self.joint_model() != JointModel::Multibody {
            return Err(format!(
                "'actuators[{k}]': a kinematic actuator needs joints = \"multibody\" (rapier's \
                 kinematic multibody joints)"
            ));
        }
        for (j, &own) in entry.iter().enumerate() {
            let name = &d.joints[j].name;
            // The entry that gave this joint its actuator, else the kinematic one.
            let k = own.unwrap_or(k);
            match spec(own) {
                Some(ActuatorSpec::Motor { .. }) => {
                    return Err(format!(
                        "'actuators[{k}]': joint '{name}' of {} takes a motor, which rapier \
                         cannot solve in a multibody with kinematic joints; make it kinematic, \
                         or use a servo, position or velocity actuator",
                        d.file
                    ));
                }
                Some(
                    ActuatorSpec::Kinematic { .. }
                    | ActuatorSpec::Rim { .. }
                    | ActuatorSpec::Servo { .. },
                ) => {}
                _ if matches!(d.joints[j].kind, JointKind::Revolute | JointKind::Prismatic) => {
                    return Err(format!(
                        "'actuators[{k}]': joint '{name}' of {} has limits, which rapier cannot \
                         hold in a multibody with kinematic joints; make it kinematic or a servo \
                         (their targets are clamped to the limits)",
                        d.file
                    ));
                }
                _ => {}
            }
        }
        Ok(())
    }
}

impl RobotSpec {
    /// The description joint indices of the `force_torque` joints, after checking that each
    /// exists and is fixed; errors start with the quoted key.
    pub fn sensed_joints(&self, d: &RobotDescription) -> Result<Vec<usize>, String> {
        self.force_torque
            .iter()
            .enumerate()
            .map(|(k, name)| {
                let j = d.joint(name).ok_or_else(|| {
                    format!(
                        "'force_torque[{k}]': no joint named '{name}' in {} (joints: {})",
                        d.file,
                        names(d)
                    )
                })?;
                if d.joints[j].kind != JointKind::Fixed {
                    return Err(format!(
                        "'force_torque[{k}]': joint '{name}' of {} moves; a force–torque \
                         sensor sits on a fixed joint (a moving joint reports its effort in \
                         joint_states)",
                        d.file
                    ));
                }
                Ok(j)
            })
            .collect()
    }
}

fn names(d: &RobotDescription) -> String {
    d.joints
        .iter()
        .map(|j| j.name.as_str())
        .collect::<Vec<_>>()
        .join(", ")
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
