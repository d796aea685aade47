//! Reading a recording back.

use anyhow::{Context, Result};
use std::path::Path;

/// One recorded message.
pub struct RecordedMessage {
    pub topic: String,
    pub json: serde_json::Value,
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
