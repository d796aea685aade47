//! Messages between an episodic environment and its agent, in Gymnasium's terms: the
//! environment publishes each step's observation and reward (and whether the episode ended),
//! the agent answers with an action, and each finished episode is summed up once.

use crate::describe::Describe;
use crate::{FixedString, FixedVec};
use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};
use serde::Serialize;

/// Most numbers in an observation.
pub const MAX_OBSERVATION: usize = 32;
/// Most numbers in a continuous action.
pub const MAX_ACTION: usize = 8;
/// Most named values in an [`EpisodeEnd`].
pub const MAX_EPISODE_METRICS: usize = 16;

/// A short name (a metric, an outcome).
pub type ShortName = FixedString<28>;

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

/// A named number.
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::NamedValue")]
pub struct NamedValue {
    pub name: ShortName,
    pub value: f64,
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
