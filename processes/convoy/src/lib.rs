//! The convoy scenario (launch files in `launch/convoy/`):
//! - [`agent`]: the leader's goal-to-goal driver and the reference follower law, run as the
//!   `caravan-convoy-agent` node;
//! - [`monitor`]: the convoy's gaps and cross-track errors as the run goes, on
//!   `convoy/metrics` (`caravan-convoy-monitor`), with the definitions of [`measures`];
//! - [`report`]: the `convoy` and `slam` report sections (`caravan-convoy-report`);
//! - [`bench`]: how the convoy scales with its size and how long its autonomy pipeline takes
//!   (`caravan-convoy-bench scale | pipeline`).

pub mod agent;
pub mod bench;
pub mod measures;
pub mod monitor;
pub mod report;
