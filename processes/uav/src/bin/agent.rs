//! `caravan-uav-agent`: a policy as a process. On every `agent/observation` it answers with an
//! action on `agent/action` (none once the episode has ended). Params:
//! `{ policy = "do_nothing" | "side_step" | "mlp", weights = "policies/td3.json", encounter = { … } }`
//! (`weights`, relative to the launch file, for `mlp`: a trained actor).

use caravan::{Node, NodeIdentity, Trigger};
use caravan_uav::encounter::{Action, Encounter};
use caravan_uav::messages::{AgentAction, agent_action, agent_observation};
use caravan_uav::mlp::Mlp;
use caravan_uav::policy::{DoNothing, Policy, SideStep};
use serde::Deserialize;
use std::process::ExitCode;

fn main() -> ExitCode {
    caravan::node_main("caravan-uav-agent", setup, run)
}

#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
struct Params {
    /// The policy: `do_nothing`, `side_step`, or `mlp` (a trained actor from `weights`).
    policy: String,
    /// The actor's weights file (JSON), relative to the launch file; needed by `mlp`.
    #[serde(default)]
    weights: Option<String>,
    /// The encounter's constants; keep them equal to the environment's.
    #[serde(default)]
    encounter: Encounter,
}

fn setup(p: Params, identity: &NodeIdentity) -> Result<Box<dyn Policy>, String> {
    caravan_uav::ranges::encounter(&p.encounter)?;
    Ok(match p.policy.as_str() {
        "do_nothing" => Box::new(DoNothing),
        "side_step" => Box::new(SideStep::new(&p.encounter)),
        "mlp" => {
            let path = p
                .weights
                .ok_or("key 'weights': the policy 'mlp' needs a weights file")?;
            let mlp = Mlp::read(&identity.resolve_path(&path), 6)
                .map_err(|e| format!("key 'weights': {path}: {e}"))?;
            if mlp.outputs() != 2 {
                return Err(format!(
                    "key 'weights': {path}: 2 outputs expected, got {}",
                    mlp.outputs()
                ));
            }
            Box::new(mlp)
        }
        other => {
            return Err(format!(
                "key 'policy': '{other}' is not one of do_nothing, side_step, mlp"
            ));
        }
    })
}

fn run(mut node: Node, mut policy: Box<dyn Policy>) -> Result<(), caravan::Error> {
    let observations = node.subscriber(&agent_observation())?;
    let actions = node.publisher(&agent_action())?;
    let trigger = node.trigger(Trigger::on(agent_observation().name()))?;
    node.run(trigger, |_| {
        while let Some(o) = observations.receive()? {
            if o.step == 0 {
                policy.reset();
            }
            if o.terminated != 0 || o.truncated != 0 {
                continue;
            }
            let obs = o.observation.as_slice();
            let Ok(obs) = <[f64; 6]>::try_from(obs) else {
                return Err(caravan::Error::Step(format!(
                    "agent/observation holds {} numbers; the encounter has 6",
                    obs.len()
                )));
            };
            let mut a = caravan_schemas::placement_new::<AgentAction>();
            a.episode = o.episode;
            a.step = o.step;
            match policy.act(&obs) {
                Action::Discrete(i) => a.discrete = i as i32,
                Action::Continuous(c) => {
                    a.discrete = -1;
                    a.continuous.set_from_slice(&c);
                }
            }
            actions.publish(&a)?;
        }
        Ok(())
    })?;
    Ok(())
}
