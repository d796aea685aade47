//! The node's params, from the launch file's `params` table.
//!
//! ```toml
//! params = { world = "worlds/lab.toml", urdf = "robots/convoy_bot.urdf", count = 2,
//!            poses = [[2.2, 1.0, 0.0], [1.8, 1.0, 0.0]], substeps = 5,
//!            motor = { resistance_ohm = 20.0 }, pid = { kp = 0.2, ki = 2.0 } }
//! ```
//!
//! `world` is required, and so are the robots: `robots = [...]` ([`RobotSpec`]) describes
//! robots of any kind, several kinds in one world; the top-level keys (`urdf` and `count`,
//! both required, and `poses`, `lifted`, `wheel_friction`, `motor`, `pid`) describe robots
//! of one kind instead: a differential drive on `dc_motor` actuators, the `robots` entry of
//! [`RobotSpec::dc_motor_diff_drive`]. Robots are numbered in order across kinds: robot i
//! publishes on `robot/i/…`.

use crate::firmware::FirmwareParams;
use crate::motor::MotorParams;
use crate::spec::RobotSpec;
use serde::Deserialize;

/// Floating-point precision of the physics.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, serde::Serialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Precision {
    /// rapier3d (f32): the fast default.
    #[default]
    F32,
    /// rapier3d-f64 with parry3d-f64: for experiments whose accuracy needs it (an IMU read at
    /// 1e-6 m/s²).
    F64,
}

/// `robots`, refused when given empty.
fn non_empty_robots<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Option<Vec<RobotSpec>>, D::Error> {
    let robots = Vec::<RobotSpec>::deserialize(d)?;
    if robots.is_empty() {
        return Err(serde::de::Error::custom(
            "an empty list; give at least one robot",
        ));
    }
    Ok(Some(robots))
}

/// The params as given. [`Default`] is every key left out, which [`Params::validate`]
/// refuses: the world and the robots have no default.
#[derive(Debug, Clone, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    /// World file, relative to the launch file's directory. Required.
    pub world: Option<String>,
    /// Robot description (URDF) of the one-kind form, relative to the launch file's
    /// directory. Required with any other top-level robot key.
    pub urdf: Option<String>,
    /// Number of robots of the one-kind form, 1 … 170 (170 = the lockstep protocol's 512 topics
    /// per step ÷ 3). Required with `urdf`.
    pub count: Option<usize>,
    /// Start pose `[x, y, theta]` (m, m, rad; finite) of each robot in the map frame; if given,
    /// exactly `count` entries. Empty: the world file's `[[start]]` poses, the first `count` of
    /// them (the world must have at least `count`).
    pub poses: Vec<[f64; 3]>,
    /// Physics steps per node step, 1 … 100, and at most the node period in ns (100 Hz node × 5
    /// = 500 Hz physics by default).
    pub substeps: u32,
    /// rapier's solver iterations (substeps of its TGS solver) per physics step, 1–64.
    /// The default 8 suits the convoy's light wheels on impulse joints; a multibody robot
    /// (exact joints) often needs 2.
    pub solver_iterations: usize,
    /// Hold every chassis in the air so the wheels spin freely: the motor bench test.
    pub lifted: bool,
    /// Coulomb friction coefficient between tyre and floor, > 0, ≤ 100 (default 1).
    pub wheel_friction: Option<f64>,
    /// The one-kind form's motor and firmware: the `dc_motor` actuator's keys, whose
    /// defaults are the measured motor and firmware of the convoy robot.
    pub motor: Option<MotorParams>,
    /// The one-kind form's wheel firmware: the `dc_motor` actuator's `pid` keys, whose defaults
    /// are the convoy robot's firmware.
    pub pid: Option<FirmwareParams>,
    /// Robots of any kind, instead of the one-kind form (never empty).
    #[serde(deserialize_with = "non_empty_robots")]
    pub robots: Option<Vec<RobotSpec>>,
    /// Gravitational acceleration along −z, m/s², 0 to 1000.
    pub gravity: f64,
    /// Number type of the physics engine: `f32` (rapier3d) or `f64` (rapier3d-f64 with
    /// parry3d-f64, for experiments whose accuracy needs it).
    pub precision: Precision,
    /// Not taken by the one-kind form (the convoy's wheeled robot): refused, naming this key.
    /// Give initial joint positions in a `robots` entry.
    pub initial_positions: Option<std::collections::BTreeMap<String, f64>>,
    /// Not taken by the one-kind form: refused, as `initial_positions`.
    pub initial_velocities: Option<std::collections::BTreeMap<String, f64>>,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            world: None,
            urdf: None,
            count: None,
            poses: Vec::new(),
            substeps: 5,
            solver_iterations: crate::robot::SOLVER_ITERATIONS,
            lifted: false,
            wheel_friction: None,
            motor: None,
            pid: None,
            robots: None,
            gravity: 9.81,
            precision: Precision::F32,
            initial_positions: None,
            initial_velocities: None,
        }
    }
}

/// Most robots one physics process simulates. Each robot adds three topics to a step's
/// publications, and the lockstep protocol carries at most `MAX_TOPICS` per step.
pub const MAX_ROBOTS: usize = (caravan_schemas::lockstep::MAX_TOPICS - 1) / 3;

impl Params {
    /// `count` robots of description `urdf` in `world` (the one-kind form), every other key
    /// left out.
    pub fn one_kind(world: &str, urdf: &str, count: usize) -> Self {
        Self {
            world: Some(world.into()),
            urdf: Some(urdf.into()),
            count: Some(count),
            ..Self::default()
        }
    }

    /// The world file as given; refused naming the key when left out.
    pub fn world(&self) -> Result<&str, String> {
        self.world.as_deref().ok_or_else(|| {
            "key 'world': missing; give the world file the robots are in, relative to the \
             launch file (e.g. world = \"worlds/lab.toml\"); there is no default world"
                .into()
        })
    }

    /// Whether any key of the one-kind form is given.
    fn one_kind_given(&self) -> bool {
        self.urdf.is_some()
            || self.count.is_some()
            || !self.poses.is_empty()
            || self.lifted
            || self.wheel_friction.is_some()
            || self.motor.is_some()
            || self.pid.is_some()
    }

    /// The kinds of robot, each with its count: `robots`, or the `robots` entry the one-kind
    /// form stands for. Refused naming the key: no robots, both forms, or `urdf` and `count`
    /// not both given.
    pub fn robot_specs(&self) -> Result<Vec<RobotSpec>, String> {
        match (&self.robots, &self.urdf, self.count) {
            (Some(_), ..) if self.one_kind_given() => Err("key 'robots': give the robots \
                 either in 'robots' or with the top-level keys (urdf, count, poses, lifted, \
                 wheel_friction, motor, pid), not both"
                .into()),
            (Some(robots), ..) => Ok(robots.clone()),
            (None, Some(urdf), Some(count)) => Ok(vec![RobotSpec::dc_motor_diff_drive(
                urdf,
                count,
                &self.poses,
                self.lifted,
                self.wheel_friction.unwrap_or(1.0),
                self.motor.unwrap_or_default(),
                self.pid.unwrap_or_default(),
            )]),
            (None, Some(urdf), None) => Err(format!(
                "key 'count': missing; give the number of robots of urdf = \"{urdf}\" (robots \
                 of one kind need both 'urdf' and 'count')"
            )),
            (None, None, _) if self.one_kind_given() => Err("key 'urdf': missing; give the \
                 robot description (robots of one kind need both 'urdf' and 'count')"
                .into()),
            (None, None, _) => Err("key 'robots': missing; give the robots as robots = \
                 [{ urdf = \"…\", … }], or robots of one kind as urdf = \"…\" and count = N; \
                 there is no default robot"
                .into()),
        }
    }

    /// Checks values serde cannot; the message names the key.
    pub fn validate(&self) -> Result<(), String> {
        self.world()?;
        for (key, given) in [
            ("initial_positions", self.initial_positions.is_some()),
            ("initial_velocities", self.initial_velocities.is_some()),
        ] {
            if given {
                return Err(format!(
                    "key '{key}': the top-level robot keys build the convoy's wheeled robot \
                     (urdf, count), which takes no initial joint state; give the robot as \
                     robots = [{{ urdf = \"…\", {key} = {{ joint = value }} }}]"
                ));
            }
        }
        let specs = self.robot_specs()?;
        // Up to 100 g: beyond it no body stays on any floor and rapier's contacts blow up.
        if !(0.0..=1000.0).contains(&self.gravity) {
            return Err(format!(
                "key 'gravity': must be 0 to 1000 (m/s², pointing down), got {}",
                self.gravity
            ));
        }
        if self.robots.is_some() {
            let total: usize = specs.iter().map(|r| r.count).sum();
            if total > MAX_ROBOTS {
                return Err(format!(
                    "key 'robots': {total} robots in all; at most {MAX_ROBOTS}"
                ));
            }
            for (k, r) in specs.iter().enumerate() {
                r.validate()
                    .map_err(|e| format!("key 'robots[{k}].{}", &e[1..]))?;
            }
            return self.validate_step();
        }
        let count = specs[0].count;
        if count == 0 || count > MAX_ROBOTS {
            return Err(format!(
                "key 'count': must be between 1 and {MAX_ROBOTS}, got {count}"
            ));
        }
        if !self.poses.is_empty() && self.poses.len() != count {
            return Err(format!(
                "key 'poses': {} start pose(s) for count = {count}; give one [x, y, theta] per \
                 robot, or none to use the world file's [[start]] poses",
                self.poses.len(),
            ));
        }
        for (i, p) in self.poses.iter().enumerate() {
            crate::spec::check_pose_values(i, p).map_err(|e| format!("key {e}"))?;
        }
        self.validate_step()?;
        crate::spec::check_wheel_friction(specs[0].wheel_friction)
            .map_err(|e| format!("key {e}"))?;
        self.motor
            .unwrap_or_default()
            .validate()
            .map_err(|e| format!("key {e}"))?;
        self.pid
            .unwrap_or_default()
            .validate()
            .map_err(|e| format!("key {e}"))?;
        Ok(())
    }

    fn validate_step(&self) -> Result<(), String> {
        if !(1..=100).contains(&self.substeps) {
            return Err(format!(
                "key 'substeps': must be between 1 and 100, got {}",
                self.substeps
            ));
        }
        if !(1..=64).contains(&self.solver_iterations) {
            return Err(format!(
                "key 'solver_iterations': must be between 1 and 64, got {}",
                self.solver_iterations
            ));
        }
        Ok(())
    }

    /// The step configuration for physics step `dt_ns`.
    pub fn sim_config(&self, dt_ns: u64) -> crate::robot::SimConfig {
        crate::robot::SimConfig {
            dt_ns,
            gravity: self.gravity,
            precision: self.precision,
            solver_iterations: self.solver_iterations,
        }
    }
}
