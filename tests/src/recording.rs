//! Reading a run's recording the way an indexed reader (Foxglove's) does: from its summary.

use std::collections::BTreeMap;
use std::path::Path;

/// One channel of a recording's summary.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChannelSummary {
    pub schema: String,
    pub encoding: String,
    pub messages: u64,
}

/// The recording at `path`, read whole.
pub fn read(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()))
}

/// The summary's channels by topic, with their message counts from the statistics; panics if
/// the file has no summary, no statistics or no chunk indexes.
pub fn channels(bytes: &[u8]) -> BTreeMap<String, ChannelSummary> {
    let summary = mcap::Summary::read(bytes)
        .expect("a readable summary")
        .expect("the recording has a summary");
    assert!(!summary.chunk_indexes.is_empty(), "no chunk indexes");
    let stats = summary.stats.as_ref().expect("summary statistics");
    summary
        .channels
        .values()
        .map(|c| {
            let schema = c
                .schema
                .as_ref()
                .map(|s| s.name.clone())
                .unwrap_or_default();
            let summary = ChannelSummary {
                schema,
                encoding: c.message_encoding.clone(),
                messages: stats
                    .channel_message_counts
                    .get(&c.id)
                    .copied()
                    .unwrap_or(0),
            };
            (c.topic.clone(), summary)
        })
        .collect()
}

/// The `run` metadata record, through the summary's metadata index.
pub fn run_metadata(bytes: &[u8]) -> BTreeMap<String, String> {
    let summary = mcap::Summary::read(bytes).unwrap().unwrap();
    let index = summary
        .metadata_indexes
        .iter()
        .find(|i| i.name == "run")
        .expect("a 'run' metadata record");
    mcap::read::metadata(bytes, index).unwrap().metadata
}

/// The attachment called `name`, through the summary's attachment index.
pub fn attachment(bytes: &[u8], name: &str) -> Vec<u8> {
    let summary = mcap::Summary::read(bytes).unwrap().unwrap();
    let index = summary
        .attachment_indexes
        .iter()
        .find(|i| i.name == name)
        .unwrap_or_else(|| panic!("no attachment {name}"));
    mcap::read::attachment(bytes, index)
        .unwrap()
        .data
        .into_owned()
}

/// Every message on `topic`, as raw bytes, in file order.
pub fn messages(bytes: &[u8], topic: &str) -> Vec<Vec<u8>> {
    mcap::MessageStream::new(bytes)
        .unwrap()
        .map(|m| m.unwrap())
        .filter(|m| m.channel.topic == topic)
        .map(|m| m.data.into_owned())
        .collect()
}

/// Every message of a recording in file order, as (channel id, topic, log time, bytes): the
/// order across topics and the channel ids count, not only each topic's messages.
pub fn all_messages(bytes: &[u8]) -> Vec<(u16, String, u64, Vec<u8>)> {
    mcap::MessageStream::new(bytes)
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            (
                m.channel.id,
                m.channel.topic.clone(),
                m.log_time,
                m.data.into_owned(),
            )
        })
        .collect()
}

/// Asserts two recordings' messages (see [`all_messages`]) are the same, naming the first
/// difference.
pub fn assert_same_messages(a: &[(u16, String, u64, Vec<u8>)], b: &[(u16, String, u64, Vec<u8>)]) {
    assert_eq!(a.len(), b.len(), "different numbers of messages");
    for (x, y) in a.iter().zip(b) {
        assert!(
            x == y,
            "first difference: {:?} against {:?}",
            (x.0, &x.1, x.2),
            (y.0, &y.1, y.2)
        );
    }
}
