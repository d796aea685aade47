//! Recording topics to MCAP, and reading recordings back.

pub mod reader;
pub mod recorder;
pub mod schema;

pub use recorder::{Recorder, Recording};
