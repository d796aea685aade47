//! `caravan-uav-env`: the head-on encounter's environment, run at the physics' rate. It starts
//! each episode (`robot/<i>/set_pose` for both drones), applies each of the agent's actions to
//! the agent's velocity (`agent/action` → `robot/0/cmd_vel`), publishes an observation and reward
//! every agent step (`agent/observation`) and sums up each finished episode (`agent/episode`).
//! After `episodes` episodes it exits, which ends the group (`ends_group = true`). The
//! episodes' rules are the library's `Episodes` (`episode.rs`); this file wires them to topics.

use caravan::{Node, NodeIdentity, Trigger};
use caravan_schemas::topics;
use caravan_uav::encounter::Encounter;
use caravan_uav::episode::{Episodes, Start};
use caravan_uav::messages::{EnvStep, agent_action, agent_episode, agent_observation};
use caravan_uav::scenario::Scenario;
use caravan_uav::world::{Frame, Truth};
use serde::Deserialize;
use std::process::ExitCode;

fn main() -> ExitCode {
    caravan::node_main("caravan-uav-env", setup, run)
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
struct Params {
    #[serde(default)]
    encounter: Encounter,
    /// `head_on`, `s1`, `s2` or `s3`.
    scenario: String,
    /// Episodes to run, 1 to `ranges::MAX_EPISODES`.
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
    caravan_uav::ranges::encounter(&p.encounter)?;
    caravan_uav::ranges::frame(&p.frame)?;
    let scenario = Scenario::named(&p.scenario).map_err(|e| format!("key 'scenario': {e}"))?;
    caravan_uav::ranges::episodes(p.episodes)?;
    Ok(Ready {
        e: p.encounter,
        scenario,
        episodes: p.episodes,
        frame: p.frame,
        seed: identity.node_seed(),
    })
}

struct Ports {
    cmd_vel: caravan::Publisher<caravan_schemas::Twist>,
    set_pose: [caravan::Publisher<caravan_schemas::Pose3D>; 2],
    observations: caravan::Publisher<EnvStep>,
}

impl Ports {
    fn start(&self, start: &Start) -> Result<(), caravan::Error> {
        self.set_pose[0].publish(&start.set_pose[0])?;
        self.set_pose[1].publish(&start.set_pose[1])?;
        self.cmd_vel.publish(&start.cmd_vel)?;
        self.observations.publish(&start.observation)
    }
}

fn run(mut node: Node, r: Ready) -> Result<(), caravan::Error> {
    let ports = Ports {
        cmd_vel: node.publisher(&topics::cmd_vel(0))?,
        set_pose: [
            node.publisher(&topics::set_pose(0))?,
            node.publisher(&topics::set_pose(1))?,
        ],
        observations: node.publisher(&agent_observation())?,
    };
    let mut truth = Truth::open(&node)?;
    let summaries = node.publisher(&agent_episode())?;
    let actions = node.subscriber(&agent_action())?;
    let mut episodes = Episodes::new(r.e, r.scenario, r.frame, r.episodes, r.seed);
    let trigger = node.trigger(Trigger::every_hz(240.0))?;
    node.run(trigger, |step| {
        let now = step.now_ns();
        let latest = truth.poll()?;
        if let Some(start) = episodes.start(now) {
            ports.start(&start)?;
        }
        // The agent's answer to the last observation moves it at once.
        while let Some(a) = actions.receive()? {
            if let Some(cmd_vel) = episodes.act(now, &a).map_err(caravan::Error::Step)? {
                ports.cmd_vel.publish(&cmd_vel)?;
            }
        }
        let Some(agent_step) = episodes.step(now, latest) else {
            return Ok(());
        };
        ports.observations.publish(&agent_step.observation)?;
        if let Some(end) = &agent_step.end {
            summaries.publish(&end.summary)?;
            match &end.next {
                Some(next) => ports.start(next)?,
                None => step.stop(),
            }
        }
        Ok(())
    })?;
    Ok(())
}
