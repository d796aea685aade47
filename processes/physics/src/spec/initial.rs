//! A robot kind's initial joint state, `initial_positions` and `initial_velocities` (joint
//! name to value, as MoveIt's `initial_positions.yaml`), checked against its description.

use super::RobotSpec;
use caravan_world::description::{JointKind, RobotDescription};
use std::collections::BTreeMap;

/// One joint's start, each value if given: position (rad or m) and velocity (rad/s or m/s).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct JointStart {
    pub position: Option<f64>,
    pub velocity: Option<f64>,
}

/// The two keys, each with its values and whether it gives positions.
fn keys(spec: &RobotSpec) -> [(&'static str, &BTreeMap<String, f64>, bool); 2] {
    [
        ("initial_positions", &spec.initial_positions, true),
        ("initial_velocities", &spec.initial_velocities, false),
    ]
}

impl RobotSpec {
    /// Every value finite; errors start with the quoted key.
    pub(super) fn check_initial_values(&self) -> Result<(), String> {
        for (key, values, _) in keys(self) {
            if let Some((name, v)) = values.iter().find(|(_, v)| !v.is_finite()) {
                return Err(format!("'{key}.{name}': must be a finite number, got {v}"));
            }
        }
        Ok(())
    }

    /// One start per joint of `d`, after checking that each named joint exists and moves and
    /// that its values lie within its URDF limits; errors start with the quoted key.
    pub fn initial_joints(&self, d: &RobotDescription) -> Result<Vec<JointStart>, String> {
        let mut starts = vec![JointStart::default(); d.joints.len()];
        for (key, values, positions) in keys(self) {
            for (name, &v) in values {
                let at = format!("'{key}.{name}'");
                let Some(j) = d.joint(name) else {
                    let movable = d.movable_joints();
                    let names = movable.iter().map(|&j| d.joints[j].name.as_str());
                    let near = names
                        .clone()
                        .map(|n| (strsim::damerau_levenshtein(n, name), n))
                        .filter(|(edits, n)| *edits <= 2.max(n.len() / 3))
                        .min()
                        .map(|(_, n)| format!("did you mean '{n}'? "))
                        .unwrap_or_default();
                    let names: Vec<_> = names.collect();
                    return Err(format!(
                        "{at}: no joint named '{name}' in {}; {near}(movable joints: {})",
                        d.file,
                        names.join(", ")
                    ));
                };
                let joint = &d.joints[j];
                let line = joint.line.map(|l| format!(":{l}")).unwrap_or_default();
                let (unit, l) = match joint.kind {
                    JointKind::Fixed => {
                        return Err(format!(
                            "{at}: joint '{name}' ({}{line}) is fixed; only revolute, \
                             continuous and prismatic joints have a position and velocity",
                            d.file
                        ));
                    }
                    JointKind::Prismatic => ("m", joint.limits),
                    _ => ("rad", joint.limits),
                };
                if positions && !(l.lower..=l.upper).contains(&v) {
                    return Err(format!(
                        "{at}: {v} {unit} is outside joint '{name}''s limits [{}, {}] {unit} \
                         ({}{line})",
                        l.lower, l.upper, d.file
                    ));
                }
                if !positions && v.abs() > l.velocity {
                    return Err(format!(
                        "{at}: {v} {unit}/s is faster than joint '{name}''s velocity limit {} \
                         {unit}/s ({}{line})",
                        l.velocity, d.file
                    ));
                }
                let start = &mut starts[j];
                *(if positions {
                    &mut start.position
                } else {
                    &mut start.velocity
                }) = Some(v);
            }
        }
        Ok(starts)
    }
}
