//! The accelerometer design the IMU reference study rejected: a test mass of m kg held by a
//! force sensor, reading a = F/m, where F is the force the sensor exerts on the mass (in the
//! mass's frame; physics' `robot/i/force_torque` for the fixed joint that holds it). At rest
//! F = m·g upwards, so it reads the specific force as the finite-difference design does.

use caravan_schemas::ForceTorques;
use nalgebra::Vector3;
use std::collections::VecDeque;

/// How many force readings are kept to pair with the IMU's states by stamp.
const KEPT: usize = 64;

/// Force readings of one joint by stamp, turned into specific force.
#[derive(Debug, Clone)]
pub struct ForceAccelerometer {
    joint: String,
    mass_kg: f64,
    recent: VecDeque<(u64, Vector3<f64>)>,
}

impl ForceAccelerometer {
    pub fn new(joint: &str, mass_kg: f64) -> Self {
        Self {
            joint: joint.to_string(),
            mass_kg,
            recent: VecDeque::with_capacity(KEPT),
        }
    }

    /// Takes a `force_torque` message stamped `stamp_ns`.
    pub fn push(&mut self, stamp_ns: u64, sensors: &ForceTorques) {
        let Some(s) = sensors
            .sensors
            .as_slice()
            .iter()
            .find(|s| s.joint.as_str() == self.joint)
        else {
            return;
        };
        if self.recent.len() == KEPT {
            self.recent.pop_front();
        }
        let f = Vector3::new(s.force.x, s.force.y, s.force.z);
        self.recent.push_back((stamp_ns, f));
    }

    /// The specific force (m/s², the mass's frame) of the reading stamped `stamp_ns`.
    pub fn specific_force(&self, stamp_ns: u64) -> Option<Vector3<f64>> {
        self.recent
            .iter()
            .rev()
            .find(|(t, _)| *t == stamp_ns)
            .map(|(_, f)| f / self.mass_kg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use caravan_schemas::{ForceTorque, Name, Vector3 as V};

    #[test]
    fn a_held_mass_reads_force_over_mass_by_stamp() {
        let mut fa = ForceAccelerometer::new("accel_joint", 2.0);
        let mut m = caravan_schemas::placement_new::<ForceTorques>();
        let reading = ForceTorque {
            joint: Name::new("accel_joint"),
            force: V {
                x: 0.0,
                y: 0.0,
                z: 19.62,
            },
            ..ForceTorque::default()
        };
        m.sensors.push(reading).unwrap();
        fa.push(7, &m);
        assert_eq!(fa.specific_force(7), Some(Vector3::new(0.0, 0.0, 9.81)));
        assert_eq!(fa.specific_force(8), None);
        let mut other = ForceAccelerometer::new("wrist", 1.0);
        other.push(7, &m);
        assert_eq!(other.specific_force(7), None);
    }
}
