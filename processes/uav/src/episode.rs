//! The environment's episodes, as the `caravan-uav-env` node runs them: a start (both drones
//! to their starts, the agent at cruise speed, the first observation), the agent's actions
//! (one per observation, applied at once), an observation and reward every agent step from
//! the drones' ground truth, and an episode's end (a collision, the floor, the pass or the
//! time limit) summed up and followed by the next episode until the last.
//!
//! The node publishes what [`Episodes`] returns; nothing here touches the runtime, so the
//! transitions are unit-tested without a group.

use crate::encounter::{Action, Encounter, Outcome, State};
use crate::messages::{AgentAction, EnvStep, EpisodeEnd};
use crate::metrics::EpisodeMetrics;
use crate::scenario::Scenario;
use crate::world::{Frame, twist};
use caravan_schemas::{NamedValue, Odometry, Pose3D, ShortName, Twist};
use caravan_sensor::noise::Gaussian;
use nalgebra::Vector3;

/// The messages that start an episode, to publish in this order.
#[derive(Debug, Clone, Copy)]
pub struct Start {
    /// The agent's and the opponent's start poses, world frame (`robot/0/set_pose`,
    /// `robot/1/set_pose`).
    pub set_pose: [Pose3D; 2],
    /// The agent's velocity, world frame, m/s (`robot/0/cmd_vel`): cruise speed along +x.
    pub cmd_vel: Twist,
    /// The episode's step-0 observation (`agent/observation`), reward 0.
    pub observation: EnvStep,
}

/// What an agent step produced, to publish in this order.
#[derive(Debug, Clone, Copy)]
pub struct AgentStep {
    /// The step's observation and reward (`agent/observation`).
    pub observation: EnvStep,
    /// The episode's end, if this step ended it.
    pub end: Option<End>,
}

/// A finished episode.
#[derive(Debug, Clone, Copy)]
pub struct End {
    /// The episode's summary (`agent/episode`).
    pub summary: EpisodeEnd,
    /// The next episode's start; `None` after the last episode: the environment is done.
    pub next: Option<Start>,
}

/// The episode under way.
struct Episode {
    number: u64,
    step: u32,
    /// When its last observation went out, and when the next is due, ns.
    observed_ns: u64,
    next_ns: u64,
    /// Whether the last observation has had its action.
    acted: bool,
    agent_v: Vector3<f64>,
    total_reward: f64,
    metrics: EpisodeMetrics,
}

/// The environment's episodes, from the first to the last.
pub struct Episodes {
    e: Encounter,
    scenario: Scenario,
    frame: Frame,
    episodes: u64,
    /// Draws each episode's start shift.
    g: Gaussian,
    current: Option<Episode>,
}

impl Episodes {
    /// `episodes` (≥ 1) episodes of encounter `e` in `scenario`, placed in the world at
    /// `frame`, their start shifts drawn from `seed`.
    pub fn new(e: Encounter, scenario: Scenario, frame: Frame, episodes: u64, seed: u64) -> Self {
        Self {
            e,
            scenario,
            frame,
            episodes,
            g: Gaussian::new(seed, 0),
            current: None,
        }
    }

    /// Starts episode 1 at `now_ns` (the node's first step); `None` once it has started.
    pub fn start(&mut self, now_ns: u64) -> Option<Start> {
        if self.current.is_some() {
            return None;
        }
        let (ep, start) = self.begin(1, now_ns);
        self.current = Some(ep);
        Some(start)
    }

    /// The agent's action `a`, arriving at `now_ns`: the agent's new velocity command, or
    /// `None` if `a` answers another observation than the last or the last already had its
    /// action. An action that is not one names what is wrong with it.
    pub fn act(&mut self, now_ns: u64, a: &AgentAction) -> Result<Option<Twist>, String> {
        let Some(ep) = &mut self.current else {
            return Ok(None);
        };
        if a.episode != ep.number || a.step != ep.step || ep.acted {
            return Ok(None);
        }
        let action = if a.discrete >= 0 {
            Action::Discrete(a.discrete.min(255) as u8)
        } else {
            let c = a.continuous.as_slice();
            Action::Continuous([
                c.first().copied().unwrap_or(f64::NAN),
                c.get(1).copied().unwrap_or(f64::NAN),
            ])
        };
        let units = action
            .units()
            .map_err(|why| format!("agent/action: {why}"))?;
        ep.agent_v = self.e.apply(&ep.agent_v, action)?;
        let cmd_vel = twist(&ep.agent_v);
        ep.metrics
            .action(units, (now_ns - ep.observed_ns) as f64 * 1e-9);
        ep.acted = true;
        Ok(Some(cmd_vel))
    }

    /// The agent step at `now_ns`, with the agent's and the opponent's latest ground truth:
    /// `None` before the step is due (steps keep their schedule from the episode's start, late
    /// or not) or before both drones' ground truth has arrived.
    pub fn step(&mut self, now_ns: u64, truth: Option<(Odometry, Odometry)>) -> Option<AgentStep> {
        let e = &self.e;
        let ep = self.current.as_mut()?;
        if now_ns < ep.next_ns {
            return None;
        }
        let (agent, opponent) = truth?;
        ep.step += 1;
        let s = self
            .frame
            .state(&agent, &opponent, ep.step as f64 * e.step_s);
        let outcome = e.outcome(&s);
        let reward = e.reward(&s, outcome);
        ep.total_reward += reward;
        ep.metrics.observe(e, &s);
        let observation = observation(e, &s, ep.number, ep.step, reward, outcome);
        ep.observed_ns = now_ns;
        ep.next_ns += e.step_ns();
        ep.acted = false;
        let end = match outcome {
            None => None,
            Some(outcome) => {
                let summary = summary(ep, outcome);
                let number = ep.number;
                // After the last episode, the ended one stays: the node stops.
                let next = (number < self.episodes).then(|| {
                    let (next, start) = self.begin(number + 1, now_ns);
                    self.current = Some(next);
                    start
                });
                Some(End { summary, next })
            }
        };
        Some(AgentStep { observation, end })
    }

    /// Episode `number` starting at `now_ns`: both drones to their starts (the opponent's
    /// shifted by the scenario), the agent at cruise speed, and the first observation.
    fn begin(&mut self, number: u64, now_ns: u64) -> (Episode, Start) {
        let e = &self.e;
        let offset = self.scenario.offset(&mut self.g);
        let start = State {
            agent: e.agent_start(),
            agent_v: Vector3::new(e.speed_m_s, 0.0, 0.0),
            opponent: e.opponent_start(offset),
            opponent_v: Vector3::new(-e.speed_m_s, 0.0, 0.0),
            t_s: 0.0,
        };
        let messages = Start {
            set_pose: [
                self.frame.pose(&start.agent),
                self.frame.pose(&start.opponent),
            ],
            cmd_vel: twist(&start.agent_v),
            observation: observation(e, &start, number, 0, 0.0, None),
        };
        let mut metrics = EpisodeMetrics::new();
        metrics.observe(e, &start);
        let ep = Episode {
            number,
            step: 0,
            observed_ns: now_ns,
            next_ns: now_ns + e.step_ns(),
            acted: false,
            agent_v: start.agent_v,
            total_reward: 0.0,
            metrics,
        };
        (ep, messages)
    }
}

fn observation(
    e: &Encounter,
    s: &State,
    number: u64,
    step: u32,
    reward: f64,
    end: Option<Outcome>,
) -> EnvStep {
    let mut m = caravan_schemas::placement_new::<EnvStep>();
    m.episode = number;
    m.step = step;
    m.terminated = matches!(end, Some(o) if o != Outcome::Timeout) as u32;
    m.truncated = (end == Some(Outcome::Timeout)) as u32;
    m.reward = reward;
    m.observation.set_from_slice(&e.observe(s));
    m
}

fn summary(ep: &Episode, outcome: Outcome) -> EpisodeEnd {
    let mut m = caravan_schemas::placement_new::<EpisodeEnd>();
    m.episode = ep.number;
    m.steps = ep.step;
    m.outcome = ShortName::new(match outcome {
        Outcome::Passed => "passed",
        Outcome::Collided => "collided",
        Outcome::Floor => "floor",
        Outcome::Timeout => "timeout",
    });
    m.total_reward = ep.total_reward;
    for (name, value) in ep.metrics.named() {
        let _ = m.metrics.push(NamedValue {
            name: ShortName::new(name),
            value,
        });
    }
    m
}

#[cfg(test)]
#[path = "episode_tests.rs"]
mod tests;
