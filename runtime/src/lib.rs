//! Caravan runtime: the library every Caravan process links.
//!
//! A [`Node`] is one process of a launched group. It opens typed [`Topic`]s as zero-copy
//! iceoryx2 publishers and subscribers, reads its typed params, and runs a step function
//! periodically or on message arrival under a real-time or lockstep clock:
//!
//! ```no_run
//! use caravan::{Node, Trigger};
//! use caravan_schemas::{topics, Pose2D};
//!
//! # fn main() -> Result<(), caravan::Error> {
//! let mut node = Node::from_env()?;
//! let pose = node.publisher(&topics::pose(0))?;
//! node.run(Trigger::every_hz(10.0), |step| {
//!     pose.publish(&Pose2D { x: step.now().as_secs_f64(), y: 0.0, theta: 0.0 })
//! })?;
//! # Ok(())
//! # }
//! ```
//!
//! A node sleeps between steps. One that answers requests at once can spin briefly before it
//! sleeps (launch key `spin`, or [`NodeBuilder::spin`]; see [`spin`]): a reply then arrives
//! in ~5 µs instead of a ~30 µs wake-up, for some CPU when nothing comes.

mod clock;
pub mod container;
pub mod discovery;
mod entry;
mod error;
mod executor;
pub mod facts;
pub mod group;
mod identity;
pub mod inject;
pub mod input;
pub mod lockstep;
pub mod log;
mod node;
mod params;
pub mod pattern;
mod publisher;
pub mod range;
mod rate;
pub mod relay;
pub mod spin;
mod stats;
mod subscriber;
pub mod tap;
mod transport;
pub mod types;
pub mod untyped;

pub use caravan_network as network;
pub use caravan_schemas as schemas;
pub use caravan_schemas::Header;
pub use caravan_schemas::{Delivery, Topic};
pub use clock::ClockMode;
pub use entry::{EXIT_BAD_INPUT, EXIT_FAILURE, node_main};
pub use error::Error;
pub use executor::Step;
pub use identity::{NodeIdentity, check_only, env_vars};
pub use node::{Node, NodeBuilder};
pub use params::{
    DESCRIBE_PARAMS_FLAG, describe_params, describe_params_requested, parse_params,
    print_params_description,
};
pub use publisher::{Loan, Publisher};
pub use rate::{MAX_DURATION, MIN_PERIOD, Trigger, parse_duration, parse_rate, seconds};
pub use schemars;
pub use spin::{MAX_SPIN, parse_spin};
pub use stats::{StepCompute, StepStats, process_cpu_ns, thread_cpu_ns};
pub use subscriber::{Received, Subscriber};

/// Wall-clock time (CLOCK_REALTIME) in nanoseconds since the Unix epoch.
pub fn wall_clock_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or(0)
}
