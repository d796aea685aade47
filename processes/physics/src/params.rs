//! The node's params, from the launch file's `params` table.
//!
//! ```toml
//! params = { world = "worlds/lab.toml", urdf = "robots/convoy_bot.urdf", count = 2,
//!            poses = [[2.2, 1.0, 0.0], [1.8, 1.0, 0.0]], substeps = 5,
//!            motor = { resistance_ohm = 20.0 }, pid = { kp = 0.2, ki = 2.0 } }
//! ```
//!
//! Every key is optional. The defaults are the reference convoy: five robots in a line along
//! y = 0.7 facing +x in the lab world, and the fitted motor and PID constants.

use crate::firmware::FirmwareParams;
use crate::motor::MotorParams;
use serde::Deserialize;

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Params {
    /// World file, relative to the launch file's directory.
    pub world: String,
    /// Robot description (URDF), relative to the launch file's directory.
    pub urdf: String,
    /// Number of robots; robot i publishes on `robot/i/…`.
    pub count: usize,
    /// Start pose `[x, y, theta]` (m, m, rad) of each robot in the map frame, one per robot.
    pub poses: Vec<[f64; 3]>,
    /// Physics steps per node step (100 Hz node × 5 = 500 Hz physics by default).
    pub substeps: u32,
    /// Hold every chassis in the air so the wheels spin freely: the motor bench test.
    pub lifted: bool,
    /// Friction coefficient between wheels and floor.
    pub wheel_friction: f64,
    pub motor: MotorParams,
    pub pid: FirmwareParams,
}

/// The reference convoy's start line: R0 (leader) in front at x = 2.2, R4 last at x = 0.6.
pub const CONVOY_START: [[f64; 3]; 5] = [
    [2.2, 1.0, 0.0],
    [1.8, 1.0, 0.0],
    [1.4, 1.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.6, 1.0, 0.0],
];

impl Default for Params {
    fn default() -> Self {
        Self {
            world: "worlds/lab.toml".into(),
            urdf: "robots/convoy_bot.urdf".into(),
            count: CONVOY_START.len(),
            poses: CONVOY_START.to_vec(),
            substeps: 5,
            lifted: false,
            wheel_friction: 1.0,
            motor: MotorParams::default(),
            pid: FirmwareParams::default(),
        }
    }
}

/// Most robots one physics process simulates. Each robot adds three topics to a step's
/// publications, and the lockstep protocol carries at most `MAX_TOPICS` per step.
pub const MAX_ROBOTS: usize = (caravan_schemas::lockstep::MAX_TOPICS - 1) / 3;

impl Params {
    /// Checks values serde cannot; the message names the key.
    pub fn validate(&self) -> Result<(), String> {
        if self.count == 0 || self.count > MAX_ROBOTS {
            return Err(format!(
                "key 'count': must be between 1 and {MAX_ROBOTS}, got {}",
                self.count
            ));
        }
        if self.poses.len() != self.count {
            let default = if self.poses == CONVOY_START {
                " (the default poses, the five-robot convoy line)"
            } else {
                ""
            };
            return Err(format!(
                "key 'poses': {} start pose(s){default} for count = {}; give one \
                 [x, y, theta] per robot",
                self.poses.len(),
                self.count
            ));
        }
        if let Some(i) = self
            .poses
            .iter()
            .position(|p| p.iter().any(|v| !v.is_finite()))
        {
            return Err(format!("key 'poses[{i}]': values must be finite numbers"));
        }
        if !(1..=100).contains(&self.substeps) {
            return Err(format!(
                "key 'substeps': must be between 1 and 100, got {}",
                self.substeps
            ));
        }
        if !(self.wheel_friction.is_finite() && self.wheel_friction > 0.0) {
            return Err(format!(
                "key 'wheel_friction': must be positive, got {}",
                self.wheel_friction
            ));
        }
        self.motor.validate().map_err(|e| format!("key {e}"))?;
        self.pid.validate().map_err(|e| format!("key {e}"))?;
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
        assert_eq!(p.poses[0], [2.2, 1.0, 0.0]);
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
    fn unknown_keys_are_rejected() {
        let e = parse(json!({"motor": {"resistance": 3.0}})).unwrap_err();
        assert!(e.contains("motor.resistance"), "{e}");
    }
}
