//! From params to a running simulation, with every input checked: the world file, each
//! robot description and its actuators, the start poses, and that no robot starts inside an
//! obstacle, off the floor, or inside another robot. Errors are one paragraph naming the
//! file or key.

use crate::actuator::Actuator;
use crate::params::Params;
use crate::robot::{self, Overlap, RobotBuild, RobotSetup, SimConfig, StartPose};
use crate::simulation::Simulation;
use crate::spec::{Drive, RobotSpec};
use caravan_world::description::{JointKind, RobotDescription, load_description};
use caravan_world::{RobotModel, load_world};
use nalgebra::{Isometry3, Vector3};
use std::fmt;
use std::path::Path;

/// Bad input; the message is meant for the author of the launch file.
#[derive(Debug, Clone, PartialEq)]
pub struct SetupError(pub String);

impl fmt::Display for SetupError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SetupError {}

/// The key prefix of robot kind `k`: `robots[k].` or nothing for the top-level form.
fn key(params: &Params, k: usize, name: &str) -> String {
    if params.robots.is_empty() {
        name.to_string()
    } else {
        format!("robots[{k}].{name}")
    }
}

/// Loads the world and the robots named in `params` (paths relative to `launch_dir`) and
/// builds the simulation with physics step `dt_ns`.
pub fn load(params: &Params, launch_dir: &Path, dt_ns: u64) -> Result<Simulation, SetupError> {
    params.validate().map_err(SetupError)?;
    let world_path = launch_dir.join(&params.world);
    let world = load_world(&world_path).map_err(|e| {
        SetupError(format!(
            "world file (key 'world' = \"{}\"): {e}",
            params.world
        ))
    })?;
    let specs = params.robot_specs();
    let mut descriptions = Vec::with_capacity(specs.len());
    for (k, spec) in specs.iter().enumerate() {
        let d = load_description(&launch_dir.join(&spec.urdf)).map_err(|e| {
            SetupError(format!(
                "robot description (key '{}' = \"{}\"): {e}",
                key(params, k, "urdf"),
                spec.urdf
            ))
        })?;
        let sensed = spec
            .sensed_joints(&d)
            .map_err(|e| SetupError(format!("key '{}{}", key(params, k, ""), &e[1..])))?;
        check_masses(&d, spec, &sensed).map_err(|e| {
            SetupError(format!(
                "robot description (key '{}' = \"{}\"): {e}",
                key(params, k, "urdf"),
                spec.urdf
            ))
        })?;
        if spec.joint_states != Some(false) || spec.link_states || spec.contacts {
            crate::messages::check_fits(&d, spec.link_states).map_err(|e| {
                SetupError(format!(
                    "robot description (key '{}' = \"{}\"): {e}",
                    key(params, k, "urdf"),
                    spec.urdf
                ))
            })?;
        }
        descriptions.push((d, sensed));
    }

    // Start poses: each kind's own, else the world's [[start]] poses in robot order.
    let total: usize = specs.iter().map(|s| s.count).sum();
    let mut poses: Vec<(String, Vec<f64>)> = Vec::with_capacity(total);
    for (k, spec) in specs.iter().enumerate() {
        for n in 0..spec.count {
            let name = key(params, k, &format!("poses[{n}]"));
            let pose = match spec.poses.get(n) {
                Some(p) => p.clone(),
                None => {
                    let g = poses.len();
                    let start = world.starts.get(g).ok_or_else(|| {
                        SetupError(format!(
                            "key '{}': not given, and world file {} has {} [[start]] pose(s) \
                             for {total} robot(s); give one pose per robot in either",
                            key(params, k, "poses"),
                            world_path.display(),
                            world.starts.len(),
                        ))
                    })?;
                    start.to_vec()
                }
            };
            poses.push((name, pose));
        }
    }
    for (g, (name, p)) in poses.iter().enumerate() {
        let (x, y) = (p[0], p[1]);
        if !(0.0..=world.size[0]).contains(&x) || !(0.0..=world.size[1]).contains(&y) {
            return Err(SetupError(format!(
                "key '{name}' = {p:?}: robot {g} would start off the floor of world '{}' \
                 ({}), which spans x ∈ [0, {}] and y ∈ [0, {}] m",
                world.name,
                world_path.display(),
                world.size[0],
                world.size[1]
            )));
        }
    }

    let mut builds = Vec::with_capacity(total);
    let mut pose_iter = poses.iter();
    for (k, (spec, (d, sensed))) in specs.iter().zip(&descriptions).enumerate() {
        // Spec errors start with the quoted key below the robot kind: 'actuators[0]…'.
        let actuators = actuators(spec, d)
            .map_err(|e| SetupError(format!("key '{}{}", key(params, k, ""), &e[1..])))?;
        let drive = match spec.drive {
            Some(Drive::Diff) => Some(diff_drive(d).map_err(|e| {
                SetupError(format!(
                    "key '{}': {e} (robot description {})",
                    key(params, k, "drive"),
                    d.file
                ))
            })?),
            None => None,
        };
        for _ in 0..spec.count {
            let (_, p) = pose_iter.next().expect("one pose per robot");
            let reflected_inertia = actuators
                .iter()
                .map(|a| a.as_ref().map_or(0.0, Actuator::reflected_inertia))
                .collect();
            let kinematic = actuators
                .iter()
                .map(|a| a.as_ref().and_then(Actuator::kinematic))
                .collect();
            builds.push(RobotBuild {
                setup: RobotSetup {
                    description: d,
                    spec,
                    pose: start_pose(p),
                    reflected_inertia,
                    kinematic,
                    sensed: sensed.clone(),
                },
                actuators: actuators.clone(),
                drive,
            });
        }
    }
    let cfg = SimConfig {
        dt_ns,
        gravity: params.gravity,
        precision: params.precision,
        solver_iterations: params.solver_iterations,
    };
    let sim = Simulation::new(&world, builds, cfg).map_err(SetupError)?;
    let topics: usize = 1
        + (0..sim.robot_count())
            .map(|i| sim.outputs(i).topic_count())
            .sum::<usize>();
    if topics > caravan_schemas::lockstep::MAX_TOPICS {
        return Err(SetupError(format!(
            "key 'robots': the robots would publish {topics} topics per step, more than the \
             {} one process may; switch off link_states or contacts, or split the robots \
             over two physics processes",
            caravan_schemas::lockstep::MAX_TOPICS
        )));
    }
    match sim.first_overlap() {
        None => Ok(sim),
        Some(Overlap::Obstacle { robot: i, obstacle }) => {
            let o = &world.obstacles[obstacle];
            Err(SetupError(format!(
                "key '{}' = {:?}: robot {i} would start inside the {} centred at ({}, {}) of \
                 world file {}; move it to free floor",
                poses[i].0,
                poses[i].1,
                robot::kind_name(o.kind),
                o.center[0],
                o.center[1],
                world_path.display()
            )))
        }
        Some(Overlap::Robot { robot: i, other: j }) => Err(SetupError(format!(
            "keys '{}' = {:?} and '{}' = {:?}: robots {i} and {j} would start inside each \
             other; space them further apart",
            poses[i].0, poses[i].1, poses[j].0, poses[j].1
        ))),
    }
}

fn start_pose(p: &[f64]) -> StartPose {
    match *p {
        [x, y, yaw] => StartPose::Planar { x, y, yaw },
        [x, y, z, roll, pitch, yaw] => StartPose::Full(Isometry3::new(
            Vector3::new(x, y, z),
            nalgebra::UnitQuaternion::from_euler_angles(roll, pitch, yaw).scaled_axis(),
        )),
        _ => unreachable!("validated: 3 or 6 numbers"),
    }
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
