//! The agent's params, from the launch file.

use crate::agent::follower::FollowerParams;
use crate::agent::leader::LeaderParams;
use caravan_schemas::MAX_ROBOT_STATES;
use serde::Deserialize;

#[derive(
    Debug, Clone, Copy, Deserialize, serde::Serialize, schemars::JsonSchema, PartialEq, Eq, Default,
)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    Leader,
    #[default]
    Follower,
    /// Only drive the Twist commands of `cmd_vel_topic` (default `robot/<i>/cmd_vel`), as
    /// ROS's diff_drive_controller does: a teleop, or a ROS 2 node through `caravan-ros2`.
    Drive,
}

#[derive(Debug, Clone, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct Params {
    /// This robot's index: 0 is the leader, i follows i − 1 by default. With a `world` that
    /// lists `[[start]]` poses: one of its robots.
    pub robot: usize,
    /// Which controller runs: `leader`, `follower` or `drive`.
    pub mode: Mode,
    /// Where the robot learns its own pose (Pose2D); default `robot/<i>/pose_true`.
    pub pose_topic: Option<String>,
    /// Where a follower learns its predecessor's pose; default `robot/<i−1>/pose_true`.
    pub predecessor_topic: Option<String>,
    /// Read the own pose and a follower's predecessor's from this one RobotStates topic,
    /// robot i at index i, instead of `pose_topic` and `predecessor_topic` (not with either):
    /// `robots/state_true`, the physics' ground truth of the whole team in one message.
    pub states_topic: Option<String>,
    /// Leader: drive the planner's velocity commands (Twist) from this topic instead of
    /// straight at the goals, e.g. `robot/0/cmd_vel`. Drive: the commands to drive.
    pub cmd_vel_topic: Option<String>,
    /// Leader with a planner, and drive: a command older than this is stale and the robot
    /// stops, s, 0.05 (one tick) to 10.
    pub cmd_vel_timeout_s: f64,
    /// The robot's URDF, relative to the launch file: wheel radius and separation, and the
    /// chassis footprint the follower keeps its distance with (required: the default `""` is
    /// rejected).
    pub urdf: String,
    /// The world file, relative to the launch file: a world that lists `[[start]]` poses
    /// names the robots, and `robot` must be one of them (any mode); a leader's goals are its
    /// `[[goal]]`s when `leader.goals` is empty.
    pub world: Option<String>,
    /// The follower's law (`mode = "follower"`).
    pub follower: FollowerParams,
    /// The leader's goals and limits (`mode = "leader"`; the limits also clamp `mode =
    /// "drive"`).
    pub leader: LeaderParams,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            robot: 0,
            mode: Mode::default(),
            pose_topic: None,
            predecessor_topic: None,
            states_topic: None,
            cmd_vel_topic: None,
            cmd_vel_timeout_s: 0.5,
            urdf: String::new(),
            world: None,
            follower: FollowerParams::default(),
            leader: LeaderParams::default(),
        }
    }
}

impl Params {
    /// Checks what serde cannot: every number's range (`ranges`), a follower needs a
    /// predecessor, a leader needs goals.
    pub fn validate(&self) -> Result<(), String> {
        crate::agent::ranges::check(self)?;
        if self.states_topic.is_some() {
            for (key, given) in [
                ("pose_topic", &self.pose_topic),
                ("predecessor_topic", &self.predecessor_topic),
            ] {
                if given.is_some() {
                    return Err(format!(
                        "key 'states_topic': the poses come from it, so '{key}' must not be given too"
                    ));
                }
            }
            if self.robot >= MAX_ROBOT_STATES {
                return Err(format!(
                    "key 'robot': {}, but the message of 'states_topic' holds robots 0 to {}",
                    self.robot,
                    MAX_ROBOT_STATES - 1
                ));
            }
            if self.mode == Mode::Follower && self.robot == 0 {
                return Err("key 'states_topic': robot 0 has no predecessor in it; make it the leader (mode = \"leader\")".into());
            }
        }
        match self.mode {
            Mode::Follower if self.robot == 0 && self.predecessor_topic.is_none() => {
                Err("key 'robot': robot 0 has no predecessor; make it the leader (mode = \"leader\") or set 'predecessor_topic'".into())
            }
            Mode::Leader if self.leader.goals.is_empty() && self.world.is_none() => Err("key 'leader.goals': a leader needs at least one goal (or a 'world' file with [[goal]]s)".into()),
            _ if self.urdf.is_empty() => Err(
                "key 'urdf': give the robot's URDF (its wheel radius and separation)".into(),
            ),
            _ => Ok(()),
        }
    }
}
