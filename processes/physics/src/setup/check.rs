//! Setup's first step: the params, the world file, and each robot description against its
//! kind's spec (its sensors, masses, actuators, drive and the topics it would publish),
//! before anything is placed or built.

use super::SetupError;
use crate::actuator::Actuator;
use crate::params::Params;
use crate::robot::Outputs;
use crate::spec::{Drive, JointStart, RobotSpec};
use caravan_world::description::{JointKind, RobotDescription, load_description};
use caravan_world::{RobotModel, World, load_world};
use std::path::{Path, PathBuf};

/// The world and the robots, kind by kind, checked.
pub struct Checked {
    pub world: World,
    /// The world file as read, for messages.
    pub world_path: PathBuf,
    pub kinds: Vec<Kind>,
}

/// One kind of robot, checked: its description and what drives its joints.
pub struct Kind {
    /// Its keys' prefix in messages: `robots[k].`, or nothing for the one-kind form.
    pub key: String,
    pub spec: RobotSpec,
    pub description: RobotDescription,
    /// The force–torque sensors' fixed joints (description indices).
    pub sensed: Vec<usize>,
    /// One per description joint.
    pub actuators: Vec<Option<Actuator>>,
    /// The left and right wheel joints of a differential drive.
    pub drive: Option<[usize; 2]>,
    /// Each joint's initial state.
    pub initial: Vec<JointStart>,
}

impl Checked {
    /// Each robot's start ([`super::place`]).
    pub fn place(&self) -> Result<Vec<super::Start>, SetupError> {
        let kinds = self.kinds.iter().map(|k| (k.key.as_str(), &k.spec));
        super::place(&self.world, &self.world_path, kinds)
    }
}

/// Checks `params` and reads the files they name (relative to `launch_dir`).
pub fn check(params: &Params, launch_dir: &Path) -> Result<Checked, SetupError> {
    params.validate().map_err(SetupError)?;
    let world_file = params.world().map_err(SetupError)?;
    let world_path = launch_dir.join(world_file);
    let world = load_world(&world_path)
        .map_err(|e| SetupError(format!("world file (key 'world' = \"{world_file}\"): {e}")))?;
    let prefix = |k: usize| match params.robots {
        Some(_) => format!("robots[{k}]."),
        None => String::new(),
    };
    let kinds = (params
        .robot_specs()
        .map_err(SetupError)?
        .into_iter()
        .enumerate())
    .map(|(k, spec)| kind(prefix(k), spec, launch_dir))
    .collect::<Result<Vec<_>, _>>()?;
    let topics: usize = 1 + kinds
        .iter()
        .map(|k| {
            let outputs = Outputs::of(&k.spec, &k.description, k.drive.is_some());
            k.spec.count * outputs.topic_count()
        })
        .sum::<usize>();
    if topics > caravan_schemas::lockstep::MAX_TOPICS {
        return Err(SetupError(format!(
            "key 'robots': the robots would publish {topics} topics per step, more than the \
             {} one process may; switch off link_states or contacts, or split the robots \
             over two physics processes",
            caravan_schemas::lockstep::MAX_TOPICS
        )));
    }
    Ok(Checked {
        world,
        world_path,
        kinds,
    })
}

/// Reads kind `spec`'s description and checks the spec against it; `key` prefixes its keys.
fn kind(key: String, spec: RobotSpec, launch_dir: &Path) -> Result<Kind, SetupError> {
    let in_file = |e: String| {
        SetupError(format!(
            "robot description (key '{key}urdf' = \"{}\"): {e}",
            spec.urdf
        ))
    };
    // Spec errors start with the quoted key below the robot kind: 'actuators[0]…'.
    let below = |e: String| SetupError(format!("key '{key}{}", &e[1..]));
    let d = load_description(&launch_dir.join(&spec.urdf)).map_err(|e| in_file(e.to_string()))?;
    let sensed = spec.sensed_joints(&d).map_err(below)?;
    check_masses(&d, &spec, &sensed).map_err(in_file)?;
    if spec.joint_states != Some(false) || spec.link_states || spec.contacts {
        crate::messages::check_fits(&d, spec.link_states).map_err(in_file)?;
    }
    let mut actuators = actuators(&spec, &d).map_err(below)?;
    let initial = spec.initial_joints(&d).map_err(below)?;
    for (a, start) in actuators.iter_mut().zip(&initial) {
        a.iter_mut().for_each(|a| a.start_at(*start));
    }
    let drive = match spec.drive {
        Some(Drive::Diff) => Some(diff_drive(&d).map_err(|e| {
            SetupError(format!(
                "key '{key}drive': {e} (robot description {})",
                d.file
            ))
        })?),
        None => None,
    };
    Ok(Kind {
        key,
        spec,
        description: d,
        sensed,
        actuators,
        drive,
        initial,
    })
}

/// Every link that moves needs mass: a body of massless links cannot be simulated.
fn check_masses(d: &RobotDescription, spec: &RobotSpec, sensed: &[usize]) -> Result<(), String> {
    let plan = crate::plan::RobotPlan::with_sensed(d, sensed);
    for (b, body) in plan.bodies.iter().enumerate() {
        let moves = b > 0 || spec.base == crate::spec::Base::Floating && !spec.lifted;
        let massive = body
            .links
            .iter()
            .any(|(l, _)| d.links[*l].inertial.is_some());
        if moves && !massive {
            let link = &d.links[body.links[0].0];
            let why = match &body.joint {
                Some(j) => format!("it moves on joint '{}'", d.joints[j.joint].name),
                None => "it is the floating base".to_string(),
            };
            return Err(d
                .error(
                    link.line,
                    format!(
                        "link '{}' needs an <inertial> with a positive mass: {why}",
                        link.name
                    ),
                )
                .to_string());
        }
    }
    Ok(())
}

/// One actuator per description joint, as the spec assigns them; errors start with the key
/// suffix after the robot's prefix.
pub(crate) fn actuators(
    spec: &RobotSpec,
    d: &RobotDescription,
) -> Result<Vec<Option<Actuator>>, String> {
    let assigned = spec.assign(d)?;
    Ok(assigned
        .iter()
        .zip(&d.joints)
        .map(|(a, j)| a.and_then(|a| Actuator::new(a, j.limits)))
        .collect())
}

/// The left and right wheel joints of a differential drive.
pub(crate) fn diff_drive(d: &RobotDescription) -> Result<[usize; 2], String> {
    let model = RobotModel::from_description(d)?;
    let find = |y: f64| {
        d.joints
            .iter()
            .position(|j| j.kind == JointKind::Continuous && j.origin.translation.vector.y == y)
            .expect("the model found it")
    };
    Ok([
        find(model.wheels[0].position[1]),
        find(model.wheels[1].position[1]),
    ])
}

#[cfg(test)]
mod tests {
    use super::super::checked;
    use serde_json::json;

    #[test]
    fn each_kind_is_read_with_its_actuators_and_keys() {
        let c = checked(json!([{ "urdf": "box.urdf" },
            { "urdf": "pendulum.urdf", "base": "fixed", "count": 2,
              "actuators": [{ "type": "effort", "joints": ["*"] }] }]))
        .unwrap();
        assert_eq!(c.world.name, "empty");
        assert_eq!(c.kinds[1].key, "robots[1].");
        assert_eq!(c.kinds[1].spec.count, 2);
        assert!(c.kinds[0].actuators.iter().all(Option::is_none));
        assert!(c.kinds[1].actuators.iter().any(Option::is_some));
    }

    #[test]
    fn errors_name_the_kinds_key() {
        let e = |robots| checked(robots).err().unwrap().0;
        let m = e(json!([{ "urdf": "box.urdf" }, { "urdf": "nowhere.urdf" }]));
        assert!(m.contains("key 'robots[1].urdf' = \"nowhere.urdf\""), "{m}");
        let m = e(json!([{ "urdf": "box.urdf", "drive": "diff" }]));
        assert!(m.starts_with("key 'robots[0].drive'"), "{m}");
        let m = e(json!([{ "urdf": "box.urdf", "force_torque": ["no_joint"] }]));
        assert!(m.starts_with("key 'robots[0].force_torque[0]'"), "{m}");
    }

    #[test]
    fn too_many_topics_are_refused_before_anything_is_built() {
        let m = checked(
            json!([{ "urdf": "box.urdf", "count": 120, "link_states": true,
            "contacts": true, "ground_truth": true }]),
        )
        .err()
        .unwrap()
        .0;
        assert!(
            m.contains("key 'robots'") && m.contains("601 topics"),
            "{m}"
        );
    }
}
