//! The convoy leader's planners, after move_base: a global planner (A* on a costmap inflated
//! by the robot's footprint) and a local Trajectory Rollout planner that turns the global path
//! into velocity commands within the leader's limits.
//!
//! The library has no runtime dependencies: the planning process feeds it maps, poses and
//! goals from its topics, and tests and benchmarks drive it directly. A planning node does,
//! in outline:
//!
//! - on each new map: [`Costmap::update`] (reuses its buffers);
//! - on a new goal, or when [`path_blocked`] reports the current path crossing an obstacle
//!   from just ahead of the robot ([`nearest_pose_index`] + 1): [`GlobalPlanner::plan`],
//!   reporting a [`PlanError`] to the operator as it is (its message says what to change),
//!   and publishing the path with [`fill_path2d`];
//! - every control period: [`LocalPlanner::command`] with the previous command, stopping
//!   (and re-planning) when it returns `None`, and stopping at the goal.
//!
//! [`Replanner`] is that outline as the planning node runs it, step by step.
//!
//! ```
//! use caravan_planning::*;
//! use caravan_schemas::Pose2D;
//!
//! // 3 × 2 m of free floor at 0.025 m per cell with a wall across the middle, open at the top.
//! let (w, h) = (120, 80);
//! let mut cells = vec![0i8; w * h];
//! for y in 0..56 {
//!     cells[y * w + 60] = 100;
//! }
//! let map = Costmap::from_cells(0.025, Pose2D::default(), w, h, &cells, &CostmapParams::default());
//! let start = Pose2D { x: 0.5, y: 0.5, theta: 0.0 };
//! let goal = Pose2D { x: 2.5, y: 0.5, theta: 0.0 };
//! let path = GlobalPlanner::new(GlobalParams::default()).plan(&map, start, goal)?;
//! assert!(path.iter().any(|p| p.y > 1.4), "goes round the wall's end");
//!
//! let (v, omega) = LocalPlanner::new(LocalParams::default())
//!     .command(&map, start, (0.0, 0.0), &path)
//!     .expect("a collision-free command");
//! assert!((0.1..=0.2).contains(&v) && (-1.5..=2.0).contains(&omega));
//! # Ok::<(), PlanError>(())
//! ```

mod costmap;
mod edt;
mod error;
mod global;
mod local;
mod path;
mod replan;
mod trace;
mod window;

pub use costmap::{Costmap, CostmapParams, FREE, INSCRIBED, LETHAL, MAX_INFLATED};
pub use error::{PlanError, Point};
pub use global::{GlobalParams, GlobalPlanner};
pub use local::{LocalParams, LocalPlanner};
pub use path::{fill_path2d, nearest_pose_index, path_blocked, path_length};
pub use replan::{Decision, Replanner};
pub use window::CellWindow;
