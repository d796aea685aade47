//! ROS 2 interop: ROS 2's standard message types as they travel (CDR, [`msgs`]), the mapping
//! of Caravan's types onto them field by field ([`mapping`]) and back ([`inverse`]), ROS names
//! and frames ([`naming`]), the bridge's entries in a launch file ([`config`]), the bridge
//! process itself (`caravan-ros2`, [`bridge`]), and rosbag2 bags ([`bag`]) of a recording's
//! messages ([`recorded`]).

pub mod bag;
pub mod bridge;
pub mod config;
pub mod inverse;
pub mod mapping;
pub mod msgs;
pub mod naming;
pub mod recorded;
pub mod ros_type;
