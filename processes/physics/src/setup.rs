//! From params to a running simulation, with every input checked: the world file, the robot
//! description, the number of start poses, and that no robot starts inside an obstacle, off
//! the floor, or inside another robot. Errors are one paragraph naming the file or key.

use crate::params::Params;
use crate::scene::{self, Overlap};
use crate::sim::{SimConfig, Simulation};
use caravan_world::{load_robot, load_world};
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

/// Loads the world and the robot named in `params` (paths relative to `launch_dir`) and
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
    let robot_path = launch_dir.join(&params.urdf);
    let robot = load_robot(&robot_path).map_err(|e| {
        SetupError(format!(
            "robot description (key 'urdf' = \"{}\"): {e}",
            params.urdf
        ))
    })?;
    // Without `poses`, the robots start where the world file says.
    let poses: Vec<[f64; 3]> = if params.poses.is_empty() {
        if world.starts.len() < params.count {
            return Err(SetupError(format!(
                "key 'poses': not given, and world file {} has {} [[start]] pose(s) for \
                 count = {}; give one [x, y, theta] per robot in either",
                world_path.display(),
                world.starts.len(),
                params.count
            )));
        }
        world.starts[..params.count].to_vec()
    } else {
        params.poses.clone()
    };
    for (i, &[x, y, _]) in poses.iter().enumerate() {
        if !(0.0..=world.size[0]).contains(&x) || !(0.0..=world.size[1]).contains(&y) {
            return Err(SetupError(format!(
                "key 'poses[{i}]' = {:?}: robot {i} would start off the floor of world '{}' \
                 ({}), which spans x ∈ [0, {}] and y ∈ [0, {}] m",
                poses[i],
                world.name,
                world_path.display(),
                world.size[0],
                world.size[1]
            )));
        }
    }
    let cfg = SimConfig {
        dt_ns,
        motor: params.motor,
        pid: params.pid,
        wheel_friction: params.wheel_friction,
        lifted: params.lifted,
    };
    let sim = Simulation::new(&world, &robot, &poses, cfg);
    match scene::first_overlap(sim.scene()) {
        None => Ok(sim),
        Some(Overlap::Obstacle { robot: i, obstacle }) => {
            let o = &world.obstacles[obstacle];
            Err(SetupError(format!(
                "key 'poses[{i}]' = {:?}: robot {i} would start inside the {} centred at \
                 ({}, {}) of world file {}; move it to free floor",
                poses[i],
                scene::kind_name(o.kind),
                o.center[0],
                o.center[1],
                world_path.display()
            )))
        }
        Some(Overlap::Robot { robot: i, other: j }) => Err(SetupError(format!(
            "keys 'poses[{i}]' = {:?} and 'poses[{j}]' = {:?}: robots {i} and {j} would \
             start inside each other; space them further apart",
            poses[i], poses[j]
        ))),
    }
}
