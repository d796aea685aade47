//! The node's params, from the launch file's `params` table.
//!
//! ```toml
//! params = { world = "worlds/lab.toml", urdf = "robots/convoy_bot.urdf", count = 2,
//!            poses = [[2.2, 1.0, 0.0], [1.8, 1.0, 0.0]], substeps = 5,
//!            motor = { resistance_ohm = 20.0 }, pid = { kp = 0.2, ki = 2.0 } }
//! ```
//!
//! Every key is optional. The defaults are the reference convoy: five robots in the lab world
//! at its start poses, and the fitted motor and PID constants. The top-level robot keys
//! (`urdf`, `count`, `poses`, `lifted`, `wheel_friction`, `motor`, `pid`) describe one kind
//! of differential-drive robot; `robots = [...]` ([`RobotSpec`]) describes any robots, of
//! several kinds, instead. Robots are numbered in order across kinds: robot i publishes on
//! `robot/i/…`.

use crate::firmware::FirmwareParams;
use crate::motor::MotorParams;
use crate::spec::RobotSpec;
use serde::Deserialize;

/// Floating-point precision of the physics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Precision {
    /// rapier3d (f32): the fast default.
    #[default]
    F32,
    /// rapier3d-f64 with parry3d-f64: for experiments whose accuracy needs it (an IMU read at
    /// 1e-6 m/s²).
    F64,
}

/// `robots`, refused when given empty: an empty list would silently mean the default robot.
fn non_empty_robots<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Vec<RobotSpec>, D::Error> {
    let robots = Vec::<RobotSpec>::deserialize(d)?;
    if robots.is_empty() {
        return Err(serde::de::Error::custom(
            "an empty list; give at least one robot, or leave 'robots' out for the convoy robot",
        ));
    }
    Ok(robots)
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    /// World file, relative to the launch file's directory.
    pub world: String,
    /// Robot description (URDF), relative to the launch file's directory.
    pub urdf: String,
    /// Number of robots; robot i publishes on `robot/i/…`.
    pub count: usize,
    /// Start pose `[x, y, theta]` (m, m, rad) of each robot in the map frame, one per robot;
    /// empty: the world file's `[[start]]` poses.
    pub poses: Vec<[f64; 3]>,
    /// Physics steps per node step (100 Hz node × 5 = 500 Hz physics by default).
    pub substeps: u32,
    /// rapier's solver iterations (substeps of its TGS solver) per physics step, 1–64.
    /// The default 8 suits the convoy's light wheels on impulse joints; a multibody robot
    /// (exact joints) often needs 2.
    pub solver_iterations: usize,
    /// Hold every chassis in the air so the wheels spin freely: the motor bench test.
    pub lifted: bool,
    /// Friction coefficient between wheels and floor.
    pub wheel_friction: f64,
    pub motor: MotorParams,
    pub pid: FirmwareParams,
    /// Robots of any kind; replaces the top-level robot keys when given (never empty: left
    /// out, the top-level keys' convoy robot is used).
    #[serde(deserialize_with = "non_empty_robots")]
    pub robots: Vec<RobotSpec>,
    /// Gravitational acceleration, m/s², along −z.
    pub gravity: f64,
    pub precision: Precision,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            world: "worlds/lab.toml".into(),
            urdf: "robots/convoy_bot.urdf".into(),
            count: 5,
            poses: Vec::new(),
            substeps: 5,
            solver_iterations: crate::robot::SOLVER_ITERATIONS,
            lifted: false,
            wheel_friction: 1.0,
            motor: MotorParams::default(),
            pid: FirmwareParams::default(),
            robots: Vec::new(),
            gravity: 9.81,
            precision: Precision::F32,
        }
    }
}

/// Most robots one physics process simulates. Each robot adds three topics to a step's
/// publications, and the lockstep protocol carries at most `MAX_TOPICS` per step.
pub const MAX_ROBOTS: usize = (caravan_schemas::lockstep::MAX_TOPICS - 1) / 3;

impl Params {
    /// The kinds of robot, each with its count: `robots`, or the top-level keys' convoy robot.
    pub fn robot_specs(&self) -> Vec<RobotSpec> {
        if !self.robots.is_empty() {
            return self.robots.clone();
        }
        vec![RobotSpec::convoy(
            &self.urdf,
            self.count,
            &self.poses,
            self.lifted,
            self.wheel_friction,
            self.motor,
            self.pid,
        )]
    }

    /// Checks values serde cannot; the message names the key.
    pub fn validate(&self) -> Result<(), String> {
        // Up to 100 g: beyond it no body stays on any floor and rapier's contacts blow up.
        if !(0.0..=1000.0).contains(&self.gravity) {
            return Err(format!(
                "key 'gravity': must be 0 to 1000 (m/s², pointing down), got {}",
                self.gravity
            ));
        }
        if !self.robots.is_empty() {
            let defaults = Params::default();
            let top_level_given = self.urdf != defaults.urdf
                || self.count != defaults.count
                || !self.poses.is_empty()
                || self.lifted
                || self.wheel_friction != defaults.wheel_friction
                || self.motor != defaults.motor
                || self.pid != defaults.pid;
            if top_level_given {
                return Err(
                    "key 'robots': give the robots either in 'robots' or with the \
                            top-level keys (urdf, count, poses, lifted, wheel_friction, motor, \
                            pid), not both"
                        .into(),
                );
            }
            let total: usize = self.robots.iter().map(|r| r.count).sum();
            if total > MAX_ROBOTS {
                return Err(format!(
                    "key 'robots': {total} robots in all; at most {MAX_ROBOTS}"
                ));
            }
            for (k, r) in self.robots.iter().enumerate() {
                r.validate()
                    .map_err(|e| format!("key 'robots[{k}].{}", &e[1..]))?;
            }
            return self.validate_step();
        }
        if self.count == 0 || self.count > MAX_ROBOTS {
            return Err(format!(
                "key 'count': must be between 1 and {MAX_ROBOTS}, got {}",
                self.count
            ));
        }
        if !self.poses.is_empty() && self.poses.len() != self.count {
            return Err(format!(
                "key 'poses': {} start pose(s) for count = {}; give one [x, y, theta] per \
                 robot, or none to use the world file's [[start]] poses",
                self.poses.len(),
                self.count
            ));
        }
        for (i, p) in self.poses.iter().enumerate() {
            crate::spec::check_pose_values(i, p).map_err(|e| format!("key {e}"))?;
        }
        self.validate_step()?;
        crate::spec::check_wheel_friction(self.wheel_friction).map_err(|e| format!("key {e}"))?;
        self.motor.validate().map_err(|e| format!("key {e}"))?;
        self.pid.validate().map_err(|e| format!("key {e}"))?;
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn parse(v: serde_json::Value) -> Result<Params, String> {
        let p: Params = caravan::parse_params("physics", &v).map_err(|e| e.to_string())?;
        p.validate()?;
        Ok(p)
    }

    #[test]
    fn defaults_are_the_convoy() {
        let p = parse(json!({})).unwrap();
        assert_eq!(p.count, 5);
        assert!(p.poses.is_empty(), "the world's start poses");
    }

    #[test]
    fn nested_motor_keys() {
        let p = parse(
            json!({"urdf": "r.urdf", "count": 1, "poses": [[1.0, 1.0, 0.0]],
                             "motor": {"gear_ratio": 50.0}, "pid": {"kp": 1.0}}),
        )
        .unwrap();
        assert_eq!(p.urdf, "r.urdf");
        assert_eq!(p.motor.gear_ratio, 50.0);
        assert_eq!(p.motor.supply_v, MotorParams::default().supply_v);
        assert_eq!(p.pid.kp, 1.0);
    }

    #[test]
    fn pose_count_mismatch_names_the_key() {
        let e = parse(json!({"count": 2, "poses": [[1.0, 1.0, 0.0]]})).unwrap_err();
        assert!(e.contains("'poses'") && e.contains("count = 2"), "{e}");
    }

    #[test]
    fn robots_of_several_kinds() {
        let p = parse(json!({"robots": [
            {"urdf": "arm.urdf", "base": "fixed", "actuators": [
                {"type": "position", "joints": ["*"], "kp": 50.0}]},
            {"urdf": "drone.urdf", "base": "kinematic", "count": 2,
             "poses": [[1.0, 1.0, 2.0, 0.0, 0.0, 0.0], [2.0, 1.0, 0.0]]}]}))
        .unwrap();
        let specs = p.robot_specs();
        assert_eq!(specs.len(), 2);
        assert_eq!(specs[1].count, 2);
        assert_eq!(specs[0].joint_model(), crate::spec::JointModel::Multibody);
        assert_eq!(specs[1].joint_model(), crate::spec::JointModel::Impulse);
    }

    #[test]
    fn an_empty_robot_list_is_an_error_not_the_default_robot() {
        let e = parse(json!({"robots": []})).unwrap_err();
        assert!(e.contains("robots") && e.contains("an empty list"), "{e}");
    }

    #[test]
    fn robot_kind_errors_name_the_key() {
        let e = parse(json!({"robots": [{"urdf": "a.urdf", "poses": [[1.0, 2.0]]}]})).unwrap_err();
        assert!(e.contains("key 'robots[0].poses[0]'"), "{e}");
        let e = parse(json!({"robots": [{"urdf": "a.urdf",
            "actuators": [{"type": "position", "joints": ["j"], "kp": -1.0}]}]}))
        .unwrap_err();
        assert!(
            e.contains("'robots[0].actuators[0]'") && e.contains("kp"),
            "{e}"
        );
        let e = parse(json!({"robots": [{"urdf": "a.urdf",
            "actuators": [{"type": "servo", "joints": ["j"], "stiffness": 0.0}]}]}))
        .unwrap_err();
        assert!(
            e.contains("'robots[0].actuators[0]'") && e.contains("stiffness"),
            "{e}"
        );
        let e = parse(json!({"robots": [{"urdf": "a.urdf",
            "actuators": [{"type": "torque", "joints": ["j"]}]}]}))
        .unwrap_err();
        assert!(e.contains("torque"), "{e}");
        let e = parse(json!({"count": 2, "robots": [{"urdf": "a.urdf"}]})).unwrap_err();
        assert!(e.contains("not both"), "{e}");
    }

    #[test]
    fn unknown_keys_are_rejected() {
        let e = parse(json!({"motor": {"resistance": 3.0}})).unwrap_err();
        assert!(e.contains("motor.resistance"), "{e}");
    }
}
