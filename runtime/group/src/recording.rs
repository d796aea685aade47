//! A recording's Caravan messages as the player reads them, from a Caravan recording
//! (`play.rs`) or a rosbag2 bag (`bag.rs`).

use anyhow::Result;
use caravan_schemas::descriptor::Descriptor;
use serde_json::Value;
use std::collections::BTreeMap;

/// One recorded message.
pub struct Recorded {
    /// The MCAP log time: the stamp in lockstep recordings, the wall clock in realtime ones.
    pub log_ns: u64,
    pub topic: String,
    /// The recorded header's fields.
    pub seq: u64,
    pub stamp_ns: u64,
    pub source_id: u64,
    pub json: Value,
    /// The message as recorded (JSON text), for byte-for-byte comparisons.
    pub data: Vec<u8>,
}

/// A recording's Caravan messages (JSON channels of a Caravan message type, whose names are
/// paths such as `caravan::Pose2D`; `status` and the Foxglove views left out).
#[derive(Default)]
pub struct Recording {
    /// Type of every selected channel, by topic; a channel without messages is listed too.
    pub types: BTreeMap<String, String>,
    /// The selected channels' messages, in log-time order.
    pub messages: Vec<Recorded>,
    /// Every Caravan channel's topic, selected or not.
    pub topics: Vec<String>,
    /// The descriptors the selected channels' schemas carry, by type name (none in a
    /// recording made before recordings carried them).
    pub descriptors: BTreeMap<String, Descriptor>,
}

impl Recording {
    /// Makes the recorded types known to the group of `config`, so that injectors can open
    /// topics of types that no process of the group knows.
    pub fn adopt_types(&self, config: &iceoryx2::config::Config) -> Result<()> {
        for d in self.descriptors.values() {
            caravan::types::adopt(config, d)?;
        }
        Ok(())
    }
}

/// Whether `patterns` (names or patterns with `*`, as in a launch file's `record`) select
/// `topic`; no patterns select every topic.
pub(crate) fn selected(patterns: &[String], topic: &str) -> bool {
    patterns.is_empty()
        || patterns
            .iter()
            .any(|p| caravan_launch::model::glob_match(p, topic))
}
