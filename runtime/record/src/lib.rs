//! Recording topics to MCAP (`caravan-report` reads recordings back), with Foxglove's
//! well-known views beside the raw channels, and the live view over Foxglove's WebSocket.

pub mod live;
pub mod recorder;
pub mod scene;
pub mod schema;
pub mod writer;

pub use recorder::{Recorder, Recording, RecordingMeta};
