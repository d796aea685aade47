use caravan_physics::Simulation;
use caravan_physics::convoy::ConvoyConfig;
use caravan_world::description::{RobotDescription, load_description};
use caravan_world::{Obstacle, ObstacleKind, RobotModel, Shape, World};
use std::path::{Path, PathBuf};

/// The convoy scenario's launch directory, against which params paths resolve.
pub fn launch_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch/convoy")
}

pub fn convoy_bot() -> RobotDescription {
    load_description(&launch_dir().join("robots/convoy_bot.urdf")).unwrap()
}

/// Wheel radius and separation of the convoy robot.
pub fn geometry() -> (f64, f64) {
    let m = RobotModel::from_description(&convoy_bot()).unwrap();
    (m.wheel_radius, m.wheel_separation())
}

/// A 4 × 4 m floor with a wall along x = `wall_x` (none if `None`).
pub fn room(wall_x: Option<f64>) -> World {
    let obstacles = wall_x
        .map(|x| Obstacle {
            kind: ObstacleKind::Wall,
            center: [x, 2.0],
            yaw: std::f64::consts::FRAC_PI_2,
            height: 0.3,
            shape: Shape::Box {
                half_x: 2.0,
                half_y: 0.025,
            },
        })
        .into_iter()
        .collect();
    World {
        name: "room".into(),
        size: [4.0, 4.0],
        obstacles,
        friction: None,
        surveys: Vec::new(),
        starts: Vec::new(),
        goals: Vec::new(),
    }
}

/// The default physics: 2 ms steps (100 Hz node × 5 substeps).
pub fn config() -> ConvoyConfig {
    ConvoyConfig::with_dt_ns(2_000_000)
}

pub fn sim(world: &World, poses: &[[f64; 3]]) -> Simulation {
    caravan_physics::convoy::simulation(world, &convoy_bot(), poses, config())
}

/// Runs for `seconds` of simulated time.
pub fn run_for(sim: &mut Simulation, seconds: f64) {
    let target = sim.time_ns() + (seconds * 1e9).round() as u64;
    sim.advance_to(target, u64::MAX);
}
