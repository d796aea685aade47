//! `caravan-uav-opponent`: flies drone 1 by its scenario's law (straight, zigzag, pursuit) on
//! `robot/1/cmd_vel`, at the physics' rate, timing each episode from its first observation on
//! `agent/observation`.

use caravan::{Node, NodeIdentity, Trigger};
use caravan_schemas::topics;
use caravan_uav::encounter::Encounter;
use caravan_uav::scenario::Scenario;
use caravan_uav::world::{Frame, Truth, twist};
use serde::Deserialize;
use std::process::ExitCode;

fn main() -> ExitCode {
    caravan::node_main("caravan-uav-opponent", setup, run)
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
struct Params {
    #[serde(default)]
    encounter: Encounter,
    /// `head_on`, `s1`, `s2` or `s3`.
    scenario: String,
    #[serde(default)]
    frame: Frame,
}

struct Ready {
    e: Encounter,
    scenario: Scenario,
    frame: Frame,
}

fn setup(p: Params, _: &NodeIdentity) -> Result<Ready, String> {
    caravan_uav::ranges::encounter(&p.encounter)?;
    caravan_uav::ranges::frame(&p.frame)?;
    Ok(Ready {
        e: p.encounter,
        scenario: Scenario::named(&p.scenario).map_err(|e| format!("key 'scenario': {e}"))?,
        frame: p.frame,
    })
}

fn run(mut node: Node, r: Ready) -> Result<(), caravan::Error> {
    let cmd_vel = node.publisher(&topics::cmd_vel(1))?;
    let mut truth = Truth::open(&node)?;
    let observations = node.subscriber(&caravan_uav::messages::agent_observation())?;
    let mut started_ns: Option<u64> = None;
    let trigger = node.trigger(Trigger::every_hz(240.0))?;
    node.run(trigger, |step| {
        while let Some(o) = observations.receive()? {
            if o.step == 0 {
                started_ns = Some(o.header().stamp_ns);
            }
        }
        let (Some(t0), Some((agent, own))) = (started_ns, truth.poll()?) else {
            return Ok(());
        };
        let t_s = step.now_ns().saturating_sub(t0) as f64 * 1e-9;
        let s = r.frame.state(&agent, &own, t_s);
        let v = r
            .scenario
            .opponent
            .velocity(r.e.speed_m_s, t_s, &s.opponent, &s.agent);
        cmd_vel.publish(&twist(&v))
    })?;
    Ok(())
}
