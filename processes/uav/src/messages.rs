//! Messages between an episodic environment and its agent, in Gymnasium's terms: the
//! environment publishes each step's observation and reward (and whether the episode ended),
//! the agent answers with an action, and each finished episode is summed up once.
//!
//! The scenario owns them: Caravan's tools learn their layouts from the descriptors the
//! processes register with their group. Their type names (`caravan::EnvStep`, …) are the ones
//! recordings made before the move carry, so those recordings still replay.

use caravan_schemas::describe::Describe;
use caravan_schemas::{FixedVec, NamedValue, ShortName, Topic};
use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};
use serde::Serialize;

/// Most numbers in an observation.
pub const MAX_OBSERVATION: usize = 32;
/// Most numbers in a continuous action.
pub const MAX_ACTION: usize = 8;
/// Most named values in an [`EpisodeEnd`].
pub const MAX_EPISODE_METRICS: usize = 16;

/// One step of an episodic environment, to its agent (`agent/observation`), as Gymnasium's
/// `reset` (step 0) and `step` return it.
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend, PlacementDefault, Serialize, Describe)]
#[type_name("caravan::EnvStep")]
pub struct EnvStep {
    /// Episode number, from 1.
    pub episode: u64,
    /// Step within the episode: 0 is the first observation, after the reset.
    pub step: u32,
    /// 1 when the episode ended by its rules at this step (Gymnasium's `terminated`).
    pub terminated: u32,
    /// 1 when it was cut short, by a time limit (Gymnasium's `truncated`).
    pub truncated: u32,
    pub _reserved: u32,
    /// Reward of the step that led here (0 at step 0).
    pub reward: f64,
    pub observation: FixedVec<f64, MAX_OBSERVATION>,
}

/// An agent's answer to one [`EnvStep`] (`agent/action`).
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend, PlacementDefault, Serialize, Describe)]
#[type_name("caravan::AgentAction")]
pub struct AgentAction {
    /// The episode and step it answers.
    pub episode: u64,
    pub step: u32,
    /// A discrete action's index; −1 when `continuous` holds the action.
    pub discrete: i32,
    pub continuous: FixedVec<f64, MAX_ACTION>,
}

/// A finished episode, summed up once (`agent/episode`).
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend, PlacementDefault, Serialize, Describe)]
#[type_name("caravan::EpisodeEnd")]
pub struct EpisodeEnd {
    pub episode: u64,
    /// Agent steps it lasted.
    pub steps: u32,
    pub _reserved: u32,
    /// How it ended, in the environment's words (e.g. `passed`, `collided`, `timeout`).
    pub outcome: ShortName,
    /// Sum of its rewards.
    pub total_reward: f64,
    /// The environment's measures of it (units in the names).
    pub metrics: FixedVec<NamedValue, MAX_EPISODE_METRICS>,
}

/// An episodic environment's steps, to its agent (`agent/observation`).
pub fn agent_observation() -> Topic<EnvStep> {
    Topic::new("agent/observation")
}
/// The agent's actions (`agent/action`).
pub fn agent_action() -> Topic<AgentAction> {
    Topic::new("agent/action")
}
/// Each finished episode, summed up (`agent/episode`).
pub fn agent_episode() -> Topic<EpisodeEnd> {
    Topic::new("agent/episode")
}

/// What the Python package's Gymnasium environment (`python/caravan/gym_env.py`) knows of these
/// messages, which `caravan.schemas` does not hold: their descriptors and topics. The package
/// ships it as `python/caravan/uav_messages.json`; a test keeps the two equal.
pub fn python_json() -> serde_json::Value {
    use caravan_schemas::descriptor_of;
    serde_json::json!({
        "types": [
            descriptor_of::<EnvStep>().to_json(),
            descriptor_of::<AgentAction>().to_json(),
            descriptor_of::<EpisodeEnd>().to_json(),
        ],
        "topics": {
            "AGENT_OBSERVATION": agent_observation().name(),
            "AGENT_ACTION": agent_action().name(),
            "AGENT_EPISODE": agent_episode().name(),
        },
    })
}

#[cfg(test)]
mod tests {
    /// The file the Python package ships, from this crate's directory.
    const SHIPPED: &str = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../python/caravan/uav_messages.json"
    );

    #[test]
    fn the_python_package_ships_these_messages() {
        let ours = super::python_json();
        if std::env::var_os("CARAVAN_REGENERATE").is_some() {
            let text = serde_json::to_string_pretty(&ours).unwrap() + "\n";
            std::fs::write(SHIPPED, text).unwrap();
        }
        let shipped: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(SHIPPED).unwrap()).unwrap();
        assert!(
            shipped == ours,
            "python/caravan/uav_messages.json is stale; regenerate it with \
             CARAVAN_REGENERATE=1 cargo test -p caravan-uav the_python_package_ships"
        );
    }
}
