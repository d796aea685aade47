//! Recording topics to MCAP (`caravan-report` reads recordings back).

pub mod command;
pub mod info;
pub mod live;
pub mod recorder;
pub mod scene;
pub mod schema;
pub mod writer;

pub use recorder::{Recorder, Recording, RecordingMeta};
