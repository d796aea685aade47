//! Topic names, ROS style and scoped by robot. Use these helpers instead of string literals so
//! that a typo is a compile error, not a silent missing connection.

/// Per-node execution statistics ([`crate::NodeStatus`]).
pub const STATUS: &str = "status";
/// The shared occupancy map ([`crate::OccupancyGrid`]).
pub const MAP: &str = "map";
/// The current operator goal ([`crate::Goal`]).
pub const GOAL: &str = "goal";
/// Contacts between robots and with obstacles ([`crate::Collision`]).
pub const COLLISIONS: &str = "collisions";

fn robot(i: usize, leaf: &str) -> String {
    format!("robot/{i}/{leaf}")
}

pub fn scan(i: usize) -> String {
    robot(i, "scan")
}
pub fn imu(i: usize) -> String {
    robot(i, "imu")
}
pub fn pose_true(i: usize) -> String {
    robot(i, "pose_true")
}
pub fn twist_true(i: usize) -> String {
    robot(i, "twist_true")
}
pub fn pose(i: usize) -> String {
    robot(i, "pose")
}
pub fn odometry(i: usize) -> String {
    robot(i, "odometry")
}
pub fn wheel_setpoint(i: usize) -> String {
    robot(i, "wheel_setpoint")
}
pub fn wheel_state(i: usize) -> String {
    robot(i, "wheel_state")
}
pub fn encoder_ticks(i: usize) -> String {
    robot(i, "encoder_ticks")
}
pub fn cmd_vel(i: usize) -> String {
    robot(i, "cmd_vel")
}
pub fn path(i: usize) -> String {
    robot(i, "path")
}

#[cfg(test)]
mod tests {
    #[test]
    fn robot_topics_are_scoped() {
        assert_eq!(super::scan(0), "robot/0/scan");
        assert_eq!(super::wheel_setpoint(3), "robot/3/wheel_setpoint");
    }
}
