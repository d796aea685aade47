//! Recording topics to MCAP (`caravan-report` reads recordings back).

pub mod command;
pub mod recorder;
pub mod schema;

pub use recorder::{Recorder, Recording};
