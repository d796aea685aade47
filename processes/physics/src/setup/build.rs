//! Setup's last step: the bodies of the checked robots at their starts, refusing a robot
//! that would start inside an obstacle or another robot (which the bodies tell).

use super::{Checked, SetupError, Start};
use crate::actuator::Actuator;
use crate::robot::{self, Overlap, RobotBuild, RobotSetup, SimConfig};
use crate::simulation::Simulation;

/// The simulation of `checked`'s robots, robot i at `starts[i]`.
pub fn build(
    checked: &Checked,
    starts: &[Start],
    cfg: SimConfig,
) -> Result<Simulation, SetupError> {
    let mut builds = Vec::with_capacity(starts.len());
    let mut next = starts.iter();
    for kind in &checked.kinds {
        let reflected_inertia: Vec<f64> = (kind.actuators.iter())
            .map(|a| a.as_ref().map_or(0.0, Actuator::reflected_inertia))
            .collect();
        let kinematic: Vec<_> = (kind.actuators.iter())
            .map(|a| a.as_ref().and_then(Actuator::kinematic))
            .collect();
        for _ in 0..kind.spec.count {
            let start = next.next().expect("one start per robot");
            builds.push(RobotBuild {
                setup: RobotSetup {
                    description: &kind.description,
                    spec: &kind.spec,
                    pose: start.pose(),
                    reflected_inertia: reflected_inertia.clone(),
                    kinematic: kinematic.clone(),
                    sensed: kind.sensed.clone(),
                    initial: kind.initial.clone(),
                },
                actuators: kind.actuators.clone(),
                drive: kind.drive,
            });
        }
    }
    let sim = Simulation::new(&checked.world, builds, cfg).map_err(SetupError)?;
    let world_path = checked.world_path.display();
    match sim.first_overlap() {
        None => Ok(sim),
        Some(Overlap::Obstacle { robot: i, obstacle }) => {
            let o = &checked.world.obstacles[obstacle];
            Err(SetupError(format!(
                "key '{}' = {:?}: robot {i} would start inside the {} centred at ({}, {}) of \
                 world file {world_path}; move it to free floor",
                starts[i].key,
                starts[i].given,
                robot::kind_name(o.kind),
                o.center[0],
                o.center[1],
            )))
        }
        Some(Overlap::Robot { robot: i, other: j }) => Err(SetupError(format!(
            "keys '{}' = {:?} and '{}' = {:?}: robots {i} and {j} would start inside each \
             other; space them further apart",
            starts[i].key, starts[i].given, starts[j].key, starts[j].given
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::super::checked;
    use super::*;
    use serde_json::json;

    fn built(robots: serde_json::Value) -> Result<Simulation, String> {
        let c = checked(robots).unwrap();
        let starts = c.place().unwrap();
        build(&c, &starts, SimConfig::with_dt_ns(1_000_000)).map_err(|e| e.0)
    }

    #[test]
    fn robots_are_built_in_order_at_their_starts() {
        let sim = built(json!([{ "urdf": "box.urdf", "poses": [[1.0, 1.0, 0.0]] },
            { "urdf": "pendulum.urdf", "base": "fixed", "count": 2,
              "poses": [[3.0, 1.0, 0.0], [3.0, 3.0, 0.0]] }]))
        .unwrap();
        assert_eq!(sim.robot_count(), 3);
        assert_eq!((sim.pose(0).x, sim.pose(2).y), (1.0, 3.0));
        assert!(sim.outputs(2).joint_states && !sim.outputs(0).joint_states);
    }

    #[test]
    fn robots_inside_each_other_are_refused_naming_both_keys() {
        let Err(e) = built(json!([{ "urdf": "box.urdf", "poses": [[1.0, 1.0, 0.0]] },
            { "urdf": "box.urdf", "poses": [[1.05, 1.0, 0.0]] }]))
        else {
            panic!("built")
        };
        assert!(
            e.starts_with("keys 'robots[0].poses[0]' = [1.0, 1.0, 0.0] and 'robots[1].poses[0]'")
                && e.contains("robots 0 and 1"),
            "{e}"
        );
    }
}
