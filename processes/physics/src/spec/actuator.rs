//! The actuators a robot kind gives its joints: `actuators = [{ type = …, joints = […] }]`.

use crate::firmware::FirmwareParams;
use crate::motor::MotorParams;
use serde::Deserialize;

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

    pub(super) fn validate(&self) -> Result<(), String> {
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
