//! `caravan-ros2`: the ROS 2 bridge, a node of the group that speaks DDS to ROS 2 (see
//! docs/ros2.md for its params and the mapping of types).

use caravan_ros2::config::{Config, Params};

fn main() -> std::process::ExitCode {
    caravan::node_main(
        "caravan-ros2",
        |p: Params, _| Config::check(p, std::env::var("ROS_DOMAIN_ID").ok().as_deref()),
        caravan_ros2::bridge::run,
    )
}
