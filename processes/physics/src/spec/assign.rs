//! A robot kind's spec against its description: which actuator drives each joint, which
//! fixed joints carry force–torque sensors.

use super::{ActuatorSpec, JointModel, RobotSpec};
use caravan_world::description::{JointKind, RobotDescription};

impl RobotSpec {
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
