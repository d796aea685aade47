//! Reading a run's recording back: every message as its topic and its JSON value.

use anyhow::{Context, Result};
use std::path::Path;

/// One recorded message.
pub struct RecordedMessage {
    pub topic: String,
    /// The message as JSON, with its `header` (`seq`, `stamp_ns`, `source_id`).
    pub json: serde_json::Value,
}

/// A `u64` as the recorder writes it: an integer, or a decimal string where JavaScript readers
/// would round the integer (`source_id`, `send_wall_ns`).
pub fn as_u64(v: &serde_json::Value) -> Option<u64> {
    v.as_u64().or_else(|| v.as_str()?.parse().ok())
}

impl RecordedMessage {
    /// The message's simulated stamp, ns (0 if it has none).
    pub fn stamp_ns(&self) -> u64 {
        self.header_u64("stamp_ns").unwrap_or(0)
    }

    /// A header field (`seq`, `stamp_ns`, `source_id`, `send_wall_ns`), whether written as an
    /// integer or as a decimal string.
    pub fn header_u64(&self, key: &str) -> Option<u64> {
        as_u64(&self.json["header"][key])
    }

    /// A numeric field of the message (0 when missing).
    pub fn f64(&self, key: &str) -> f64 {
        self.json[key].as_f64().unwrap_or(0.0)
    }
}

std::thread_local!(static GUARDED: std::cell::Cell<u32> = const { std::cell::Cell::new(0) });

/// Runs `read`, a reading of a recording through the mcap crate, with a panic inside it made
/// an error: the crate adds and subtracts a damaged file's offsets and lengths unchecked in
/// several places (the recording fuzz test keeps finding new ones), and a damaged file is bad
/// input, never a crash. The panic's own message is not printed; the error says `what` (the
/// file) is damaged. Errors `read` returns are passed on as they are.
pub fn guarded<T>(what: impl std::fmt::Display, read: impl FnOnce() -> Result<T>) -> Result<T> {
    static QUIET_HOOK: std::sync::Once = std::sync::Once::new();
    QUIET_HOOK.call_once(|| {
        let earlier = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if GUARDED.with(|g| g.get()) == 0 {
                earlier(info)
            }
        }));
    });
    GUARDED.with(|g| g.set(g.get() + 1));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(read));
    GUARDED.with(|g| g.set(g.get() - 1));
    result.unwrap_or_else(|_| {
        Err(anyhow::anyhow!(
            "{what} is damaged: its records do not fit together"
        ))
    })
}

/// All messages of `path` on Caravan's own (JSON) channels, in file order; the Foxglove scene
/// channels beside them are views of the same messages.
pub fn read_all(path: &Path) -> Result<Vec<RecordedMessage>> {
    guarded(path.display(), || read_all_unguarded(path))
}

fn read_all_unguarded(path: &Path) -> Result<Vec<RecordedMessage>> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut out = Vec::new();
    let at = || path.display().to_string();
    for message in mcap::MessageStream::new(&bytes).with_context(at)? {
        let message = message.with_context(at)?;
        if message.channel.message_encoding != "json" {
            continue;
        }
        out.push(RecordedMessage {
            topic: message.channel.topic.clone(),
            json: serde_json::from_slice(&message.data)
                .with_context(|| format!("message on {} is not JSON", message.channel.topic))?,
        });
    }
    Ok(out)
}
