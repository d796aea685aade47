//! What the simulated world is made of, shared by physics, sensors, planners and reports:
//! world files (floor, walls, boxes, cylinders), robot descriptions from URDF, and the
//! differential-drive kinematics of the convoy robots.

pub mod description;
pub mod geometry;
pub mod kinematics;
pub mod limits;
pub mod robot;
pub mod scene;
pub mod world;

pub use robot::{RobotError, RobotModel, load_robot};
pub use world::{Obstacle, ObstacleKind, Shape, Survey, Waypoint, World, WorldError, load_world};
