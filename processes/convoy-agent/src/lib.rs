//! Convoy agents: the follower law (`follower`), the pose history it reads from
//! (`history`), and the leader's goal-to-goal driver (`leader`). `main.rs` is plumbing.

pub mod angle;
pub mod follower;
pub mod history;
pub mod leader;
pub mod params;
