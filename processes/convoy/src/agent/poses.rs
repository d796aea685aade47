//! Where an agent reads poses: each robot's own `Pose2D` topic (`pose_topic`,
//! `predecessor_topic`), or one `RobotStates` topic that carries the whole team
//! (`states_topic`, e.g. the physics' `robots/state_true`). Both give a step the same poses:
//! every predecessor pose since the last step, and the newest own pose.

use crate::agent::params::{Mode, Params};
use caravan::{Error, Node, Subscriber, Topic};
use caravan_schemas::{Pose2D, RobotStates, topics};
use std::cell::Cell;

/// The agent's pose inputs.
// One per agent, made once: the variants' sizes do not matter.
#[allow(clippy::large_enum_variant)]
pub enum Poses {
    /// A topic per robot; the predecessor's for a follower only.
    Topics {
        own: Subscriber<Pose2D>,
        predecessor: Option<Subscriber<Pose2D>>,
    },
    /// One message with every robot, robot `i` at index `i`.
    Team {
        states: Subscriber<RobotStates>,
        own: usize,
        predecessor: Option<usize>,
        /// A message without this robot was met (and said once).
        missing: Cell<bool>,
    },
}

impl Poses {
    /// Opens what `p` names: `states_topic`, else `pose_topic` (default `robot/<i>/pose_true`)
    /// and, for a follower, `predecessor_topic` (default `robot/<i−1>/pose_true`).
    pub fn open(node: &Node, p: &Params) -> Result<Self, Error> {
        let follower = p.mode == Mode::Follower;
        if let Some(name) = &p.states_topic {
            return Ok(Self::Team {
                states: node.subscriber(&Topic::new(name))?,
                own: p.robot,
                predecessor: follower.then(|| p.robot - 1),
                missing: Cell::new(false),
            });
        }
        let own = match &p.pose_topic {
            Some(name) => Topic::new(name),
            None => topics::pose_true(p.robot),
        };
        // A follower is robot 1 or later, or names its predecessor's topic (`Params::validate`).
        let predecessor = || match &p.predecessor_topic {
            Some(name) => node.subscriber(&Topic::new(name)),
            None => node.subscriber(&topics::pose_true(p.robot - 1)),
        };
        Ok(Self::Topics {
            own: node.subscriber(&own)?,
            predecessor: follower.then(predecessor).transpose()?,
        })
    }

    /// What arrived since the last step: each predecessor pose, oldest first, goes to
    /// `predecessor` with its time (s); returns the newest own pose with its time.
    pub fn read(
        &self,
        mut predecessor: impl FnMut(f64, Pose2D),
    ) -> Result<Option<(f64, Pose2D)>, Error> {
        let secs = |stamp_ns: u64| stamp_ns as f64 * 1e-9;
        match self {
            Self::Topics {
                own,
                predecessor: before,
            } => {
                if let Some(before) = before {
                    while let Some(msg) = before.receive()? {
                        predecessor(secs(msg.header().stamp_ns), *msg);
                    }
                }
                Ok(own.latest()?.map(|msg| (secs(msg.header().stamp_ns), *msg)))
            }
            Self::Team {
                states,
                own,
                predecessor: before,
                missing,
            } => {
                let mut newest = None;
                while let Some(msg) = states.receive()? {
                    let t = secs(msg.header().stamp_ns);
                    let robots = msg.robots.as_slice();
                    if let Some(state) = before.and_then(|j| robots.get(j)) {
                        predecessor(t, state.pose);
                    }
                    match robots.get(*own) {
                        Some(state) => newest = Some((t, state.pose)),
                        // A team smaller than the robot's index: it would stand still unsaid.
                        None if !missing.replace(true) => eprintln!(
                            "caravan-convoy-agent: {}: a message of {} robots, without robot \
                             {own}: it gets no pose",
                            states.topic(),
                            robots.len()
                        ),
                        None => {}
                    }
                }
                Ok(newest)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use caravan_schemas::{MAX_ROBOT_STATES, RobotState, Twist};

    fn pose(x: f64) -> Pose2D {
        Pose2D {
            x,
            y: 0.0,
            theta: 0.0,
        }
    }

    fn follower(robot: usize) -> Params {
        Params {
            robot,
            urdf: "robot.urdf".into(),
            ..Params::default()
        }
    }

    #[test]
    fn the_team_topic_gives_what_the_robots_topics_give() {
        let group = format!("poses-{}", std::process::id());
        let node = Node::builder(&group, "agent").build().unwrap();
        let team = node.publisher(&topics::robot_states_true()).unwrap();
        let robots: Vec<_> = (0..3)
            .map(|i| node.publisher(&topics::pose_true(i)).unwrap())
            .collect();
        let by_topics = Poses::open(&node, &follower(2)).unwrap();
        let p = Params {
            states_topic: Some("robots/state_true".into()),
            ..follower(2)
        };
        let by_team = Poses::open(&node, &p).unwrap();
        for step in 0..2 {
            let mut states = RobotStates::default();
            for (i, out) in robots.iter().enumerate() {
                let x = (10 * step + i) as f64;
                out.publish(&pose(x)).unwrap();
                let state = RobotState {
                    pose: pose(x),
                    twist: Twist::default(),
                };
                states.robots.push(state).unwrap();
            }
            team.publish(&states).unwrap();
        }
        let read = |poses: &Poses| {
            let mut before = Vec::new();
            let own = poses
                .read(|_, p| before.push(p.x))
                .unwrap()
                .map(|(_, p)| p.x);
            (before, own)
        };
        let expected = (vec![1.0, 11.0], Some(12.0));
        assert_eq!(read(&by_topics), expected);
        assert_eq!(read(&by_team), expected);
        // Nothing new: no predecessor pose, no own pose.
        assert_eq!(read(&by_team), (vec![], None));
        // A team message without this robot gives its predecessor's pose, not its own.
        let mut short = RobotStates::default();
        for x in [20.0, 21.0] {
            let state = RobotState {
                pose: pose(x),
                twist: Twist::default(),
            };
            short.robots.push(state).unwrap();
        }
        team.publish(&short).unwrap();
        assert_eq!(read(&by_team), (vec![21.0], None));
        drop((by_topics, by_team, robots, team, node));
        let _ = caravan::group::remove_resources(&group);
    }

    #[test]
    fn the_team_topic_is_refused_beside_a_robots_topic() {
        for key in ["pose_topic", "predecessor_topic"] {
            let mut p = Params {
                states_topic: Some("robots/state_true".into()),
                ..follower(2)
            };
            match key {
                "pose_topic" => p.pose_topic = Some("robot/2/pose".into()),
                _ => p.predecessor_topic = Some("robot/1/pose".into()),
            }
            let err = p.validate().unwrap_err();
            assert!(err.contains("'states_topic'") && err.contains(key), "{err}");
        }
        // A robot the message cannot hold, and a follower with no predecessor in it.
        let team = |robot| Params {
            states_topic: Some("robots/state_true".into()),
            ..follower(robot)
        };
        let err = team(MAX_ROBOT_STATES).validate().unwrap_err();
        assert!(
            err.contains("'robot'") && err.contains("states_topic"),
            "{err}"
        );
        let err = team(0).validate().unwrap_err();
        assert!(
            err.contains("'states_topic'") && err.contains("leader"),
            "{err}"
        );
        assert!(team(MAX_ROBOT_STATES - 1).validate().is_ok());
    }
}
