//! The well-known topics, ROS style and scoped by robot, each bound to its message type. Open
//! them through these helpers (`node.subscriber(&topics::pose(i))`) instead of pairing a
//! string with a type at every call site: a typo or a wrong type is then a compile error, not
//! a silent missing connection or a port iceoryx2 rejects at run time.
//!
//! Every topic here uses [`Topic::new`]'s delivery ([`crate::Delivery::Latest`], depth 8).
//! Where only the name is needed (matching recorded messages), use [`Topic::name`].

use crate::{
    Collision, Contacts, EncoderTicks, ForceTorques, Goal, Imu, JointCommand, JointState,
    LaserScan, LinkStates, NodeStatus, OccupancyGrid, Odometry, Path2D, Pose2D, Pose3D,
    RobotStates, Topic, Twist, WheelSetpoint, WheelState, Wrench,
};

/// Per-node execution statistics, published by every node (`status`).
pub fn status() -> Topic<NodeStatus> {
    Topic::new("status")
}
/// The shared occupancy map (`map`).
pub fn map() -> Topic<OccupancyGrid> {
    Topic::new("map")
}
/// The world's solids, for viewers (`scene`), published by the physics.
pub fn scene() -> Topic<crate::Scene> {
    Topic::new("scene")
}
/// The current operator goal (`goal`).
pub fn goal() -> Topic<Goal> {
    Topic::new("goal")
}
/// Contacts between robots and with obstacles (`collisions`).
pub fn collisions() -> Topic<Collision> {
    Topic::new("collisions")
}
/// Every robot's ground-truth pose and velocity in one message, from the simulator
/// (`robots/state_true`): what the robots' `pose_true` and `twist_true` carry.
pub fn robot_states_true() -> Topic<RobotStates> {
    Topic::new("robots/state_true")
}

fn robot<T: crate::Message>(i: usize, leaf: &str) -> Topic<T> {
    Topic::new(&format!("robot/{i}/{leaf}"))
}

/// Robot `i`'s laser scans (`robot/i/scan`).
pub fn scan(i: usize) -> Topic<LaserScan> {
    robot(i, "scan")
}
/// Robot `i`'s IMU readings (`robot/i/imu`).
pub fn imu(i: usize) -> Topic<Imu> {
    robot(i, "imu")
}
/// Robot `i`'s ground-truth pose from the simulator (`robot/i/pose_true`).
pub fn pose_true(i: usize) -> Topic<Pose2D> {
    robot(i, "pose_true")
}
/// Robot `i`'s ground-truth velocity from the simulator (`robot/i/twist_true`).
pub fn twist_true(i: usize) -> Topic<Twist> {
    robot(i, "twist_true")
}
/// Robot `i`'s estimated pose (`robot/i/pose`).
pub fn pose(i: usize) -> Topic<Pose2D> {
    robot(i, "pose")
}
/// Robot `i`'s wheel odometry (`robot/i/odometry`).
pub fn odometry(i: usize) -> Topic<Odometry> {
    robot(i, "odometry")
}
/// Wheel speeds commanded to robot `i` (`robot/i/wheel_setpoint`).
pub fn wheel_setpoint(i: usize) -> Topic<WheelSetpoint> {
    robot(i, "wheel_setpoint")
}
/// Robot `i`'s simulated wheel speeds (`robot/i/wheel_state`).
pub fn wheel_state(i: usize) -> Topic<WheelState> {
    robot(i, "wheel_state")
}
/// Robot `i`'s wheel encoder counts (`robot/i/encoder_ticks`).
pub fn encoder_ticks(i: usize) -> Topic<EncoderTicks> {
    robot(i, "encoder_ticks")
}
/// Velocity commanded to robot `i` (`robot/i/cmd_vel`).
pub fn cmd_vel(i: usize) -> Topic<Twist> {
    robot(i, "cmd_vel")
}
/// Robot `i`'s planned path (`robot/i/path`).
pub fn path(i: usize) -> Topic<Path2D> {
    robot(i, "path")
}
/// Robot `i`'s joint readings (`robot/i/joint_states`).
pub fn joint_states(i: usize) -> Topic<JointState> {
    robot(i, "joint_states")
}
/// Targets for robot `i`'s joint actuators (`robot/i/joint_command`).
pub fn joint_command(i: usize) -> Topic<JointCommand> {
    robot(i, "joint_command")
}
/// Ground-truth poses and velocities of robot `i`'s links (`robot/i/link_states`).
pub fn link_states(i: usize) -> Topic<LinkStates> {
    robot(i, "link_states")
}
/// Robot `i`'s contact points and normal forces (`robot/i/contacts`).
pub fn contacts(i: usize) -> Topic<Contacts> {
    robot(i, "contacts")
}
/// Robot `i`'s force–torque sensors (`robot/i/force_torque`).
pub fn force_torque(i: usize) -> Topic<ForceTorques> {
    robot(i, "force_torque")
}
/// Robot `i`'s true 3-D pose and velocity (`robot/i/ground_truth`), as Gazebo's p3d plugin:
/// base_link in the map frame, twist in the map frame.
pub fn ground_truth(i: usize) -> Topic<Odometry> {
    robot(i, "ground_truth")
}
/// Forces applied to robot `i`'s links (`robot/i/wrench`).
pub fn wrench(i: usize) -> Topic<Wrench> {
    robot(i, "wrench")
}
/// Moves kinematic robot `i` to a pose at once, at rest (`robot/i/set_pose`): a new episode
/// without restarting the group, as Gazebo's `set_entity_state`.
pub fn set_pose(i: usize) -> Topic<Pose3D> {
    robot(i, "set_pose")
}

/// `robot/<i>/<leaf>` as `(i, leaf)`: the robot a per-robot topic belongs to.
pub fn robot_of(topic: &str) -> Option<(usize, &str)> {
    let (index, leaf) = topic.strip_prefix("robot/")?.split_once('/')?;
    Some((index.parse().ok()?, leaf))
}

/// The frame of robot `i`'s `link` (`robot_3/base_link`), as the recording's `tf` channel and
/// the ROS 2 bridge name it; the map frame is `map`.
pub fn robot_frame(i: usize, link: &str) -> String {
    format!("robot_{i}/{link}")
}

/// The frame a robot's pose topic places: `robot/i/pose` and `robot/i/odometry` the estimate
/// (`robot_i/base_link`), `robot/i/pose_true` and `robot/i/ground_truth` the truth
/// (`robot_i/base_link_true`); `None` for another topic.
pub fn pose_frame(topic: &str) -> Option<String> {
    match robot_of(topic)? {
        (i, "pose" | "odometry") => Some(robot_frame(i, "base_link")),
        (i, "pose_true" | "ground_truth") => Some(robot_frame(i, "base_link_true")),
        _ => None,
    }
}

/// The message type of a well-known topic (`robot/3/scan` → `caravan::LaserScan`); `None` for
/// a topic these helpers do not name. Tools that pair a topic named in a file with a type
/// (the ROS 2 bridge) check it here before anything starts.
pub fn type_of(topic: &str) -> Option<&'static str> {
    let i = robot_of(topic).map_or(0, |(i, _)| i);
    macro_rules! find {
        ($($global:ident),* ; $($per_robot:ident),*) => {
            $(if $global().name() == topic { return Some($global().type_name()); })*
            $(if $per_robot(i).name() == topic { return Some($per_robot(i).type_name()); })*
        };
    }
    find!(status, map, scene, goal, collisions;
        scan, imu, pose_true, twist_true, pose, odometry, wheel_setpoint, wheel_state,
        encoder_ticks, cmd_vel, path, joint_states, joint_command, link_states, contacts,
        force_torque, ground_truth, wrench, set_pose);
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Delivery, Message, type_name};

    fn check<T: Message>(topic: Topic<T>, name: &str) {
        assert_eq!(topic.name(), name);
        assert_eq!(topic.type_name(), type_name::<T>());
        assert_eq!(topic.delivery(), Delivery::Latest { depth: 8 }, "{name}");
    }

    #[test]
    fn well_known_topics_name_their_types() {
        assert_eq!(type_of("robot/12/scan"), Some(type_name::<LaserScan>()));
        assert_eq!(type_of("map"), Some(type_name::<OccupancyGrid>()));
        assert_eq!(type_of("robot/0/cmd_vel"), Some(type_name::<Twist>()));
        assert_eq!(type_of("robot/x/scan"), None);
        assert_eq!(type_of("robot/0/mine"), None);
        assert_eq!(robot_of("robot/3/pose_true"), Some((3, "pose_true")));
        assert_eq!(robot_of("robots/3/pose"), None);
        assert_eq!(
            pose_frame("robot/2/pose").as_deref(),
            Some("robot_2/base_link")
        );
        assert_eq!(
            pose_frame("robot/2/ground_truth").as_deref(),
            Some("robot_2/base_link_true")
        );
        assert_eq!(pose_frame("robot/2/path"), None);
    }

    #[test]
    fn robot_topics_are_scoped_and_typed() {
        check::<LaserScan>(scan(3), "robot/3/scan");
        check::<Imu>(imu(3), "robot/3/imu");
        check::<Pose2D>(pose_true(3), "robot/3/pose_true");
        check::<Twist>(twist_true(3), "robot/3/twist_true");
        check::<Pose2D>(pose(3), "robot/3/pose");
        check::<Odometry>(odometry(3), "robot/3/odometry");
        check::<WheelSetpoint>(wheel_setpoint(3), "robot/3/wheel_setpoint");
        check::<WheelState>(wheel_state(3), "robot/3/wheel_state");
        check::<EncoderTicks>(encoder_ticks(3), "robot/3/encoder_ticks");
        check::<Twist>(cmd_vel(3), "robot/3/cmd_vel");
        check::<Path2D>(path(3), "robot/3/path");
        check::<JointState>(joint_states(3), "robot/3/joint_states");
        check::<JointCommand>(joint_command(3), "robot/3/joint_command");
        check::<LinkStates>(link_states(3), "robot/3/link_states");
        check::<Contacts>(contacts(3), "robot/3/contacts");
        check::<Wrench>(wrench(3), "robot/3/wrench");
        check::<Pose3D>(set_pose(3), "robot/3/set_pose");
        check::<ForceTorques>(force_torque(3), "robot/3/force_torque");
        check::<Odometry>(ground_truth(3), "robot/3/ground_truth");
        assert_eq!(scan(0).name(), "robot/0/scan");
    }

    #[test]
    fn global_topics_are_typed() {
        check::<NodeStatus>(status(), "status");
        check::<OccupancyGrid>(map(), "map");
        check::<Goal>(goal(), "goal");
        check::<Collision>(collisions(), "collisions");
        check::<RobotStates>(robot_states_true(), "robots/state_true");
        assert_eq!(scan(0).type_name(), "caravan::LaserScan");
    }

    #[test]
    fn name_hash_is_the_lockstep_hash() {
        let topic = pose(1);
        assert_eq!(
            topic.name_hash(),
            crate::lockstep::name_hash("robot/1/pose")
        );
    }
}
