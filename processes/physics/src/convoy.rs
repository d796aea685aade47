//! The convoy robot on its DC motors without a launch file, for tests and the motor bench:
//! what the params' top-level keys build.

use crate::firmware::FirmwareParams;
use crate::motor::MotorParams;
use crate::robot::{RobotBuild, RobotSetup, SimConfig, StartPose};
use crate::simulation::Simulation;
use crate::spec::RobotSpec;
use caravan_world::World;
use caravan_world::description::RobotDescription;

/// The convoy robot's dynamics besides the world and its description.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConvoyConfig {
    /// Physics step, ns.
    pub dt_ns: u64,
    pub motor: MotorParams,
    pub pid: FirmwareParams,
    pub wheel_friction: f64,
    /// Chassis held in the air, wheels spinning freely.
    pub lifted: bool,
}

impl ConvoyConfig {
    /// Fitted defaults with physics step `dt_ns`.
    pub fn with_dt_ns(dt_ns: u64) -> Self {
        Self {
            dt_ns,
            motor: MotorParams::default(),
            pid: FirmwareParams::default(),
            wheel_friction: 1.0,
            lifted: false,
        }
    }
}

/// One convoy robot per start pose `[x, y, yaw]`, unchecked (see [`crate::setup`]).
pub fn simulation(
    world: &World,
    d: &RobotDescription,
    poses: &[[f64; 3]],
    cfg: ConvoyConfig,
) -> Simulation {
    let spec = RobotSpec::dc_motor_diff_drive(
        &d.file,
        poses.len(),
        poses,
        cfg.lifted,
        cfg.wheel_friction,
        cfg.motor,
        cfg.pid,
    );
    let actuators =
        crate::setup::check::actuators(&spec, d).expect("the convoy spec fits its robot");
    let drive = crate::setup::check::diff_drive(d).expect("a differential drive");
    let reflected: Vec<f64> = actuators
        .iter()
        .map(|a| a.as_ref().map_or(0.0, |a| a.reflected_inertia()))
        .collect();
    let builds = poses
        .iter()
        .map(|&[x, y, yaw]| RobotBuild {
            setup: RobotSetup {
                description: d,
                spec: &spec,
                pose: StartPose::Planar { x, y, yaw },
                reflected_inertia: reflected.clone(),
                kinematic: Vec::new(),
                sensed: Vec::new(),
                initial: Vec::new(),
            },
            actuators: actuators.clone(),
            drive: Some(drive),
        })
        .collect();
    let sim_cfg = SimConfig {
        dt_ns: cfg.dt_ns,
        gravity: 9.81,
        precision: crate::params::Precision::F32,
        solver_iterations: crate::robot::SOLVER_ITERATIONS,
    };
    Simulation::new(world, builds, sim_cfg).expect("the convoy robot builds")
}
