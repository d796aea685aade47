//! Reading a run's recording back: every message as its topic and its JSON value.

use anyhow::{Context, Result};
use std::path::Path;

/// One recorded message.
pub struct RecordedMessage {
    pub topic: String,
    /// The message as JSON, with its `header` (`seq`, `stamp_ns`, `source_id`).
    pub json: serde_json::Value,
}

impl RecordedMessage {
    /// The message's simulated stamp, ns (0 if it has none).
    pub fn stamp_ns(&self) -> u64 {
        self.json["header"]["stamp_ns"].as_u64().unwrap_or(0)
    }

    /// A numeric field of the message (0 when missing).
    pub fn f64(&self, key: &str) -> f64 {
        self.json[key].as_f64().unwrap_or(0.0)
    }
}

/// All messages of `path`, in file order.
pub fn read_all(path: &Path) -> Result<Vec<RecordedMessage>> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut out = Vec::new();
    for message in mcap::MessageStream::new(&bytes)? {
        let message = message?;
        out.push(RecordedMessage {
            topic: message.channel.topic.clone(),
            json: serde_json::from_slice(&message.data)
                .with_context(|| format!("message on {} is not JSON", message.channel.topic))?,
        });
    }
    Ok(out)
}
