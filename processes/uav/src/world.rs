//! Between the encounter's frame and the group's: where the encounter sits in the world, the
//! drones' ground truth as a [`State`], and velocity and pose commands.

use crate::encounter::State;
use caravan_schemas::{Odometry, Pose3D, Quaternion, Twist, Vector3 as V3, topics};
use nalgebra::Vector3;
use serde::Deserialize;

/// The encounter's frame in the world: its origin (x, y), m; z is the world's.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Frame {
    /// The encounter's origin (x, y) in the world, m, each within ±10 000; z is the world's.
    pub origin: [f64; 2],
}

impl Default for Frame {
    /// 2 m into a world's x and 4 m into its y, so a 14 × 8 m world holds the encounter.
    fn default() -> Self {
        Self { origin: [2.0, 4.0] }
    }
}

fn v(p: &V3) -> Vector3<f64> {
    Vector3::new(p.x, p.y, p.z)
}

impl Frame {
    fn offset(&self) -> Vector3<f64> {
        Vector3::new(self.origin[0], self.origin[1], 0.0)
    }

    /// The state of the two drones' ground truth, `t_s` into the episode.
    pub fn state(&self, agent: &Odometry, opponent: &Odometry, t_s: f64) -> State {
        State {
            agent: v(&agent.pose.position) - self.offset(),
            agent_v: v(&agent.twist.linear),
            opponent: v(&opponent.pose.position) - self.offset(),
            opponent_v: v(&opponent.twist.linear),
            t_s,
        }
    }

    /// The world pose of an encounter position, level.
    pub fn pose(&self, at: &Vector3<f64>) -> Pose3D {
        let w = at + self.offset();
        Pose3D {
            position: V3 {
                x: w.x,
                y: w.y,
                z: w.z,
            },
            orientation: Quaternion {
                w: 1.0,
                ..Quaternion::default()
            },
        }
    }
}

/// A world-frame velocity command.
pub fn twist(v: &Vector3<f64>) -> Twist {
    Twist {
        linear: V3 {
            x: v.x,
            y: v.y,
            z: v.z,
        },
        ..Twist::default()
    }
}

/// Both drones' latest ground truth (`robot/0/ground_truth`, `robot/1/ground_truth`).
pub struct Truth {
    subscribers: [caravan::Subscriber<Odometry>; 2],
    last: [Option<Odometry>; 2],
}

impl Truth {
    pub fn open(node: &caravan::Node) -> Result<Self, caravan::Error> {
        Ok(Self {
            subscribers: [
                node.subscriber(&topics::ground_truth(0))?,
                node.subscriber(&topics::ground_truth(1))?,
            ],
            last: [None, None],
        })
    }

    /// The agent's and the opponent's newest ground truth, once both have arrived.
    pub fn poll(&mut self) -> Result<Option<(Odometry, Odometry)>, caravan::Error> {
        for (slot, sub) in self.last.iter_mut().zip(&self.subscribers) {
            if let Some(m) = sub.latest()? {
                *slot = Some(*m);
            }
        }
        Ok(match self.last {
            [Some(a), Some(o)] => Some((a, o)),
            _ => None,
        })
    }
}
