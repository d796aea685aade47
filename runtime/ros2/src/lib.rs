//! ROS 2 interop: ROS 2's standard message types as they travel (CDR, [`msgs`]), the mapping
//! of Caravan's types onto them field by field ([`mapping`]), ROS names and frames
//! ([`naming`]), the bridge's entries in a launch file ([`config`]) and the bridge process
//! itself (`caravan-ros2`, [`bridge`]).

pub mod bridge;
pub mod config;
pub mod mapping;
pub mod msgs;
pub mod naming;
pub mod ros_type;
