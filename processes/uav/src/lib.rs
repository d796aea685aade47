//! Two-UAV collision avoidance after `shared/reference/uav-avoidance.md`, as a Caravan
//! scenario: two quadcopters fly head-on at a constant forward speed, the agent changes only
//! its lateral and vertical velocity, and must pass the other without touching it or the
//! floor while staying close to its start line.
//!
//! - [`curve`]: learning curves of training logs;
//! - [`encounter`]: the environment's constants, actions, observation, reward and episode ends;
//! - [`episode`]: the environment node's episodes: start, actions, steps, ends;
//! - [`metrics`]: the measures of an episode the reference never took;
//! - [`mlp`]: a trained actor, run without the training stack;
//! - [`opponent`]: the scripted opponents (straight, zigzag, pursuit);
//! - [`scenario`]: the evaluation scenarios (the training head-on, S1, S2, S3) and their starts;
//! - [`policy`]: the policy interface and the sanity baselines (do nothing, side-step);
//! - [`world`]: between the encounter's frame and the group's;
//! - [`ranges`]: the physical ranges of the processes' params, checked before the start;
//! - [`report`]: the report plugin's `uav` section;
//! - [`rollout`]: episodes of the encounter's own kinematics, for unit tests of the rules.

pub mod curve;
pub mod encounter;
pub mod episode;
pub mod messages;
pub mod metrics;
pub mod mlp;
pub mod opponent;
pub mod policy;
pub mod ranges;
pub mod report;
pub mod rollout;
pub mod scenario;
pub mod world;
