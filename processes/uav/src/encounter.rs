//! The head-on encounter's rules, exactly as the reference states them, with every constant
//! it leaves open chosen here, documented and a parameter ([`Encounter`]).
//!
//! The agent (drone 0) starts at (0, 0, altitude) flying +x; the opponent (drone 1) at
//! (separation, Δy, altitude + Δz) flying −x, both at `speed`. Each agent step the action
//! changes the agent's v_y and v_z by an increment; its v_x stays `speed`.
//!
//! - Observation (6 numbers in [−1, 1]): own velocity / `velocity_scale` and the opponent's
//!   position relative to own / `separation`, each clipped. The opponent's velocity is not
//!   observed.
//! - Reward each step: −(|y₀ − y| + |z₀ − z|), the agent's distance from its start line (m);
//!   colliding with the opponent or the floor: −1000 and the episode ends; passing the
//!   opponent's start x: +1000 and the episode ends. Beyond the reference: a time limit ends
//!   an episode with no bonus.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// The encounter's constants. The reference gives none of them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Encounter {
    /// Forward speed of both drones, m/s, > 0.
    pub speed_m_s: f64,
    /// Start distance along x, m, > 0.
    pub separation_m: f64,
    /// Start height of the agent, m, > `floor_m`.
    pub altitude_m: f64,
    /// The drones collide when their centres come closer than this, m, > 0 (two 0.25 m
    /// spheres, a small quadcopter with its propeller guards and a margin).
    pub collision_radius_m: f64,
    /// The agent touches the floor below this height, m, ≥ 0.
    pub floor_m: f64,
    /// Time per agent step, s, > 0 (the physics runs 10 steps of 1/240 s, PyBullet's step).
    pub step_s: f64,
    /// Velocity change of one action unit per step, m/s, > 0.
    pub dv_m_s: f64,
    /// Largest lateral and vertical speed of the agent, m/s, > 0.
    pub v_max_m_s: f64,
    /// Observed velocities are divided by this, m/s, > 0.
    pub velocity_scale_m_s: f64,
    /// Episodes end undecided after this long, s, > 0.
    pub time_limit_s: f64,
    /// Reward for passing and penalty for colliding.
    pub terminal_reward: f64,
}

impl Default for Encounter {
    fn default() -> Self {
        Self {
            speed_m_s: 1.0,
            separation_m: 10.0,
            altitude_m: 2.0,
            collision_radius_m: 0.5,
            floor_m: 0.1,
            step_s: 1.0 / 24.0,
            dv_m_s: 0.05,
            v_max_m_s: 1.0,
            velocity_scale_m_s: 1.0,
            time_limit_s: 15.0,
            terminal_reward: 1000.0,
        }
    }
}

/// What the agent does in one step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
pub enum Action {
    /// The reference's 9 discrete actions: 0 none; 1 +y; 2 −y; 3 +z; 4 −z; 5 +y+z; 6 +y−z;
    /// 7 −y+z; 8 −y−z.
    Discrete(u8),
    /// (a_y, a_z) ∈ [−1, 1]², clipped: the increment is a·dv.
    Continuous([f64; 2]),
}

impl Action {
    /// The increment in units of dv along (y, z).
    pub fn units(self) -> Result<[f64; 2], String> {
        match self {
            Action::Discrete(a) => {
                const TABLE: [[f64; 2]; 9] = [
                    [0.0, 0.0],
                    [1.0, 0.0],
                    [-1.0, 0.0],
                    [0.0, 1.0],
                    [0.0, -1.0],
                    [1.0, 1.0],
                    [1.0, -1.0],
                    [-1.0, 1.0],
                    [-1.0, -1.0],
                ];
                TABLE
                    .get(a as usize)
                    .copied()
                    .ok_or_else(|| format!("discrete action {a} is not one of 0–8"))
            }
            Action::Continuous([y, z]) if y.is_finite() && z.is_finite() => {
                Ok([y.clamp(-1.0, 1.0), z.clamp(-1.0, 1.0)])
            }
            Action::Continuous(a) => Err(format!("continuous action {a:?} is not finite")),
        }
    }
}

/// Both drones' positions and velocities (world frame, m and m/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct State {
    pub agent: Vector3<f64>,
    pub agent_v: Vector3<f64>,
    pub opponent: Vector3<f64>,
    pub opponent_v: Vector3<f64>,
    /// Time since the episode began, s.
    pub t_s: f64,
}

/// How an episode ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// The agent passed the opponent's start x.
    Passed,
    /// The drones touched.
    Collided,
    /// The agent touched the floor.
    Floor,
    /// The time limit ran out.
    Timeout,
}

impl Encounter {
    /// Checks every constant's physical range, naming the key (`encounter.*`): see
    /// [`crate::ranges::encounter`].
    pub fn validate(&self) -> Result<(), String> {
        crate::ranges::encounter(self)
    }

    /// The agent step, whole nanoseconds (the schedule's unit).
    pub fn step_ns(&self) -> u64 {
        (self.step_s * 1e9).round() as u64
    }

    /// The agent's start position.
    pub fn agent_start(&self) -> Vector3<f64> {
        Vector3::new(0.0, 0.0, self.altitude_m)
    }

    /// The opponent's start position, shifted by `offset` = (Δy, Δz).
    pub fn opponent_start(&self, offset: [f64; 2]) -> Vector3<f64> {
        Vector3::new(self.separation_m, offset[0], self.altitude_m + offset[1])
    }

    /// The agent's velocity after `action` from `v`: v_x stays `speed`, v_y and v_z change by
    /// the action's units × dv and are held within ±v_max.
    pub fn apply(&self, v: &Vector3<f64>, action: Action) -> Result<Vector3<f64>, String> {
        let [ay, az] = action.units()?;
        let clamp = |x: f64| x.clamp(-self.v_max_m_s, self.v_max_m_s);
        Ok(Vector3::new(
            self.speed_m_s,
            clamp(v.y + ay * self.dv_m_s),
            clamp(v.z + az * self.dv_m_s),
        ))
    }

    /// The agent's observation of `s`.
    pub fn observe(&self, s: &State) -> [f64; 6] {
        let v = s.agent_v / self.velocity_scale_m_s;
        let r = (s.opponent - s.agent) / self.separation_m;
        [v.x, v.y, v.z, r.x, r.y, r.z].map(|x| x.clamp(-1.0, 1.0))
    }

    /// How the episode ends at `s`, if it does (collision first, then the floor, then the
    /// pass, then the time limit).
    pub fn outcome(&self, s: &State) -> Option<Outcome> {
        if (s.opponent - s.agent).norm() < self.collision_radius_m {
            Some(Outcome::Collided)
        } else if s.agent.z < self.floor_m {
            Some(Outcome::Floor)
        } else if s.agent.x >= self.separation_m {
            Some(Outcome::Passed)
        } else if s.t_s >= self.time_limit_s {
            Some(Outcome::Timeout)
        } else {
            None
        }
    }

    /// The step's reward at `s` with the episode ending in `outcome`.
    pub fn reward(&self, s: &State, outcome: Option<Outcome>) -> f64 {
        let start = self.agent_start();
        let deviation = -((start.y - s.agent.y).abs() + (start.z - s.agent.z).abs());
        deviation
            + match outcome {
                Some(Outcome::Passed) => self.terminal_reward,
                Some(Outcome::Collided | Outcome::Floor) => -self.terminal_reward,
                Some(Outcome::Timeout) | None => 0.0,
            }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(agent: [f64; 3], opponent: [f64; 3]) -> State {
        State {
            agent: agent.into(),
            agent_v: Vector3::new(1.0, 0.3, -0.2),
            opponent: opponent.into(),
            opponent_v: Vector3::new(-1.0, 0.0, 0.0),
            t_s: 1.0,
        }
    }

    #[test]
    fn actions_change_only_the_lateral_and_vertical_speed_within_the_limits() {
        let e = Encounter::default();
        let v = Vector3::new(1.0, 0.0, 0.98);
        // 5: +y+z, dv 0.05; z is held at v_max 1.0.
        let w = e.apply(&v, Action::Discrete(5)).unwrap();
        assert!((w - Vector3::new(1.0, 0.05, 1.0)).norm() < 1e-12, "{w}");
        let w = e.apply(&v, Action::Discrete(8)).unwrap();
        assert!((w - Vector3::new(1.0, -0.05, 0.93)).norm() < 1e-12, "{w}");
        // Continuous: clipped to [−1, 1] units.
        let w = e.apply(&v, Action::Continuous([0.5, -3.0])).unwrap();
        assert!((w - Vector3::new(1.0, 0.025, 0.93)).norm() < 1e-12, "{w}");
        assert!(e.apply(&v, Action::Discrete(9)).is_err());
        assert!(e.apply(&v, Action::Continuous([f64::NAN, 0.0])).is_err());
    }

    #[test]
    fn the_observation_is_own_velocity_and_relative_position_scaled_and_clipped() {
        let e = Encounter::default();
        let s = state([2.0, 0.5, 2.0], [6.0, -0.5, 3.0]);
        let o = e.observe(&s);
        let expected = [1.0, 0.3, -0.2, 0.4, -0.1, 0.1];
        for (a, b) in o.iter().zip(expected) {
            assert!((a - b).abs() < 1e-12, "{o:?}");
        }
        let far = state([0.0, 0.0, 2.0], [30.0, 0.0, 2.0]);
        assert_eq!(e.observe(&far)[3], 1.0);
    }

    #[test]
    fn rewards_and_episode_ends_follow_the_reference() {
        let e = Encounter::default();
        // 0.5 m right of and 1 m above the start line: −1.5 per step.
        let s = state([3.0, 0.5, 3.0], [7.0, 0.0, 2.0]);
        assert_eq!(e.outcome(&s), None);
        assert!((e.reward(&s, None) + 1.5).abs() < 1e-12);
        // Centres 0.4 m apart: collided, −1000 on top.
        let hit = state([5.0, 0.0, 2.0], [5.0, 0.4, 2.0]);
        assert_eq!(e.outcome(&hit), Some(Outcome::Collided));
        assert!((e.reward(&hit, Some(Outcome::Collided)) + 1000.0).abs() < 1e-12);
        // 0.5 m apart is not a collision.
        assert_eq!(e.outcome(&state([5.0, 0.0, 2.0], [5.0, 0.5, 2.0])), None);
        let low = state([4.0, 0.0, 0.05], [6.0, 0.0, 2.0]);
        assert_eq!(e.outcome(&low), Some(Outcome::Floor));
        let passed = state([10.0, 0.0, 2.0], [0.0, 0.0, 2.0]);
        assert_eq!(e.outcome(&passed), Some(Outcome::Passed));
        assert!((e.reward(&passed, Some(Outcome::Passed)) - 1000.0).abs() < 1e-12);
        let late = State {
            t_s: 15.0,
            ..state([3.0, 2.0, 2.0], [9.0, 0.0, 2.0])
        };
        assert_eq!(e.outcome(&late), Some(Outcome::Timeout));
    }

    #[test]
    fn bad_constants_are_named() {
        let e = Encounter {
            dv_m_s: 0.0,
            ..Encounter::default()
        };
        assert!(e.validate().unwrap_err().contains("dv_m_s"));
        let e = Encounter {
            altitude_m: 0.05,
            ..Encounter::default()
        };
        assert!(e.validate().unwrap_err().contains("altitude_m"));
    }
}
