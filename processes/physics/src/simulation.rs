//! The simulation at the precision a world asks for: rapier's f32 build (the default, and
//! what the convoy's motor constants were fitted with) or its f64 build, for experiments
//! whose accuracy needs it. Both run the same engine source (`engine/`); this type forwards
//! each call to the one in use.

use crate::actuator::Target;
use crate::engine_f32::sim::Simulation as Sim32;
use crate::engine_f64::sim::Simulation as Sim64;
use crate::params::Precision;
use crate::robot::{ContactPoint, Outputs, Overlap, RobotBuild, SimConfig};
use crate::wrench::WrenchCommand;
use caravan_schemas::{Collision, Pose2D, Pose3D, Twist, WheelSetpoint, WheelState};
use caravan_world::World;
use caravan_world::description::RobotDescription;

/// Robots in a world, stepped at a fixed physics rate, in f32 or f64.
pub enum Simulation {
    F32(Box<Sim32>),
    F64(Box<Sim64>),
}

/// Forwards methods to the engine in use.
macro_rules! forward {
    ($($(#[$doc:meta])* fn $name:ident($($params:tt)*) $(-> $ret:ty)?;)*) => {
        $(forward!(@one $(#[$doc])* fn $name($($params)*) $(-> $ret)?);)*
    };
    (@one $(#[$doc:meta])* fn $name:ident(&mut $s:ident $(, $arg:ident: $ty:ty)*) $(-> $ret:ty)?) => {
        $(#[$doc])*
        pub fn $name(&mut $s $(, $arg: $ty)*) $(-> $ret)? {
            match $s {
                Simulation::F32(s) => s.$name($($arg),*),
                Simulation::F64(s) => s.$name($($arg),*),
            }
        }
    };
    (@one $(#[$doc:meta])* fn $name:ident(&$s:ident $(, $arg:ident: $ty:ty)*) $(-> $ret:ty)?) => {
        $(#[$doc])*
        pub fn $name(&$s $(, $arg: $ty)*) $(-> $ret)? {
            match $s {
                Simulation::F32(s) => s.$name($($arg),*),
                Simulation::F64(s) => s.$name($($arg),*),
            }
        }
    };
}

impl Simulation {
    /// A simulation of the given robots at `cfg.precision`. Inputs are not checked here;
    /// see [`crate::setup`].
    pub fn new(world: &World, builds: Vec<RobotBuild>, cfg: SimConfig) -> Result<Self, String> {
        Ok(match cfg.precision {
            Precision::F32 => Simulation::F32(Box::new(Sim32::new(world, builds, cfg)?)),
            Precision::F64 => Simulation::F64(Box::new(Sim64::new(world, builds, cfg)?)),
        })
    }

    /// Robot `i`'s joints in joint order: (name, position, velocity, effort).
    pub fn joints(&self, i: usize) -> Box<dyn Iterator<Item = (&str, f64, f64, f64)> + '_> {
        match self {
            Simulation::F32(s) => Box::new(s.joints(i)),
            Simulation::F64(s) => Box::new(s.joints(i)),
        }
    }

    forward! {
        fn robot_count(&self) -> usize;
        fn config(&self) -> &SimConfig;
        /// Simulated time, ns.
        fn time_ns(&self) -> u64;
        /// What robot `i` publishes.
        fn outputs(&self, i: usize) -> Outputs;
        fn description(&self, i: usize) -> &RobotDescription;
        /// Sets robot `i`'s wheel-speed set-points (rad/s); held until the next call.
        fn set_setpoint(&mut self, i: usize, sp: &WheelSetpoint);
        /// Updates robot `i`'s joint targets, in joint order; NaN fields leave a target.
        fn set_targets(&mut self, i: usize, targets: &[Target]);
        /// Sets a kinematic robot's velocity command; ignored for other bases.
        fn set_cmd_vel(&mut self, i: usize, cmd: &Twist);
        /// Moves a kinematic robot's base to a pose at once, at rest; ignored for other bases.
        fn set_pose(&mut self, i: usize, pose: &Pose3D);
        /// Starts a wrench on robot `i`; replaces the one acting on the same link.
        fn apply_wrench(&mut self, i: usize, w: &WrenchCommand) -> Result<(), String>;
        /// Advances by one physics step.
        fn step(&mut self);
        /// Steps until the next step would pass `t_ns`, at most `max_steps` times.
        fn advance_to(&mut self, t_ns: u64, max_steps: u64) -> u64;
        /// Ground-truth pose of robot `i`'s base link in the map frame.
        fn pose(&self, i: usize) -> Pose2D;
        /// Height of robot `i`'s base link above the floor, m.
        fn base_height(&self, i: usize) -> f64;
        /// Ground-truth velocity of robot `i`'s base, map frame.
        fn twist(&self, i: usize) -> Twist;
        /// Pose and twist (map frame) of robot `i`'s root link.
        fn ground_truth(&self, i: usize) -> (Pose3D, Twist);
        /// Pose (world frame) and twist of every link of robot `i`, in description order.
        fn link_states(&self, i: usize) -> Vec<(Pose3D, Twist)>;
        /// Robot `i`'s wheels; zero without a differential drive on DC motors.
        fn wheel_state(&self, i: usize) -> WheelState;
        /// Wheel speeds (left, right) the firmware measured at its last tick, rad/s.
        fn measured_speeds(&self, i: usize) -> [f64; 2];
        /// Contact events since the last call, in the order they happened.
        fn take_collisions(&mut self) -> Vec<Collision>;
        /// Pairs (robot, other robot or −1) touching now.
        fn touching(&self) -> Vec<(u32, i32)>;
        /// Contact points of robot `i`'s links after the last step.
        fn contact_points(&self, i: usize) -> Vec<ContactPoint>;
        /// The first robot that, at its start pose, overlaps an obstacle or another robot.
        fn first_overlap(&self) -> Option<Overlap>;
        /// Robot `i`'s force–torque sensors: joint, force (N) and torque (N·m) on the child,
        /// in the child link's frame.
        fn force_torque(&self, i: usize) -> Vec<(&str, [f64; 3], [f64; 3])>;
    }
}
