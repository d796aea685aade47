//! `caravan-uav-env`: the head-on encounter's environment, run at the physics' rate. It starts
//! each episode (`robot/<i>/set_pose` for both drones), applies each of the agent's actions to
//! the agent's velocity (`agent/action` → `robot/0/cmd_vel`), publishes an observation and reward
//! every agent step (`agent/observation`) and sums up each finished episode (`agent/episode`).
//! After `episodes` episodes it exits, which ends the group (`ends_group = true`).

use caravan::{Node, NodeIdentity, Trigger};
use caravan_schemas::{EnvStep, EpisodeEnd, NamedValue, ShortName, topics};
use caravan_sensor::noise::Gaussian;
use caravan_uav::encounter::{Action, Encounter, Outcome, State};
use caravan_uav::metrics::EpisodeMetrics;
use caravan_uav::scenario::Scenario;
use caravan_uav::world::{Frame, Truth, twist};
use nalgebra::Vector3;
use serde::Deserialize;
use std::process::ExitCode;

fn main() -> ExitCode {
    caravan::node_main("caravan-uav-env", setup, run)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Params {
    #[serde(default)]
    encounter: Encounter,
    /// `head_on`, `s1`, `s2` or `s3`.
    scenario: String,
    /// Episodes to run, ≥ 1.
    episodes: u64,
    #[serde(default)]
    frame: Frame,
}

struct Ready {
    e: Encounter,
    scenario: Scenario,
    episodes: u64,
    frame: Frame,
    seed: u64,
}

fn setup(p: Params, identity: &NodeIdentity) -> Result<Ready, String> {
    p.encounter
        .validate()
        .map_err(|e| format!("key 'encounter': {e}"))?;
    let scenario = Scenario::named(&p.scenario).map_err(|e| format!("key 'scenario': {e}"))?;
    if p.episodes == 0 {
        return Err("key 'episodes': at least 1".into());
    }
    Ok(Ready {
        e: p.encounter,
        scenario,
        episodes: p.episodes,
        frame: p.frame,
        seed: identity.node_seed(),
    })
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

/// Starts episode `number` at `now`: both drones to their starts (the opponent's shifted by
/// the scenario), the agent at cruise speed, and the first observation.
fn begin(
    r: &Ready,
    number: u64,
    now: u64,
    g: &mut Gaussian,
    ports: &Ports,
) -> Result<Episode, caravan::Error> {
    let e = &r.e;
    let offset = r.scenario.offset(g);
    let start = State {
        agent: e.agent_start(),
        agent_v: Vector3::new(e.speed_m_s, 0.0, 0.0),
        opponent: e.opponent_start(offset),
        opponent_v: Vector3::new(-e.speed_m_s, 0.0, 0.0),
        t_s: 0.0,
    };
    ports.set_pose[0].publish(&r.frame.pose(&start.agent))?;
    ports.set_pose[1].publish(&r.frame.pose(&start.opponent))?;
    ports.cmd_vel.publish(&twist(&start.agent_v))?;
    ports
        .observations
        .publish(&observation(e, &start, number, 0, 0.0, None))?;
    let mut metrics = EpisodeMetrics::new();
    metrics.observe(e, &start);
    Ok(Episode {
        number,
        step: 0,
        observed_ns: now,
        next_ns: now + e.step_ns(),
        acted: false,
        agent_v: start.agent_v,
        total_reward: 0.0,
        metrics,
    })
}

struct Ports {
    cmd_vel: caravan::Publisher<caravan_schemas::Twist>,
    set_pose: [caravan::Publisher<caravan_schemas::Pose3D>; 2],
    observations: caravan::Publisher<EnvStep>,
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

fn run(mut node: Node, r: Ready) -> Result<(), caravan::Error> {
    let e = r.e;
    let ports = Ports {
        cmd_vel: node.publisher(&topics::cmd_vel(0))?,
        set_pose: [
            node.publisher(&topics::set_pose(0))?,
            node.publisher(&topics::set_pose(1))?,
        ],
        observations: node.publisher(&topics::agent_observation())?,
    };
    let mut truth = Truth::open(&node)?;
    let summaries = node.publisher(&topics::agent_episode())?;
    let actions = node.subscriber(&topics::agent_action())?;
    let mut g = Gaussian::new(r.seed, 0);
    let mut ep: Option<Episode> = None;
    let trigger = node.trigger(Trigger::every_hz(240.0))?;
    node.run(trigger, |step| {
        let now = step.now_ns();
        let latest = truth.poll()?;
        let ep = match &mut ep {
            Some(ep) => ep,
            None => ep.insert(begin(&r, 1, now, &mut g, &ports)?),
        };
        // The agent's answer to the last observation moves it at once.
        while let Some(a) = actions.receive()? {
            if a.episode != ep.number || a.step != ep.step || ep.acted {
                continue;
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
                .map_err(|why| caravan::Error::Step(format!("agent/action: {why}")))?;
            ep.agent_v = e.apply(&ep.agent_v, action).map_err(caravan::Error::Step)?;
            ports.cmd_vel.publish(&twist(&ep.agent_v))?;
            ep.metrics
                .action(units, (now - ep.observed_ns) as f64 * 1e-9);
            ep.acted = true;
        }
        if now < ep.next_ns {
            return Ok(());
        }
        let Some((agent, opponent)) = latest else {
            return Ok(());
        };
        ep.step += 1;
        let s = r.frame.state(&agent, &opponent, ep.step as f64 * e.step_s);
        let outcome = e.outcome(&s);
        let reward = e.reward(&s, outcome);
        ep.total_reward += reward;
        ep.metrics.observe(&e, &s);
        ports
            .observations
            .publish(&observation(&e, &s, ep.number, ep.step, reward, outcome))?;
        ep.observed_ns = now;
        ep.next_ns += e.step_ns();
        ep.acted = false;
        if let Some(outcome) = outcome {
            summaries.publish(&summary(ep, outcome))?;
            if ep.number >= r.episodes {
                step.stop();
            } else {
                let next = ep.number + 1;
                *ep = begin(&r, next, now, &mut g, &ports)?;
            }
        }
        Ok(())
    })?;
    Ok(())
}
