//! Convoy agents: the follower law (`follower`), the pose history it reads from
//! (`history`), the leader's goal-to-goal driver (`leader`), and the node that runs either
//! (`node`), where it reads poses (`poses`); the ranges of its numeric params (`ranges`).

pub mod angle;
pub mod follower;
pub mod history;
pub mod leader;
pub mod node;
pub mod params;
pub mod poses;
pub mod ranges;
