//! What `caravan info` says of a recording (MCAP), from its summary, or read through when it
//! has none; every message is read once with each chunk's CRC checked, and the count must
//! match the summary's, so a damaged file is an error rather than described from a summary
//! that no longer holds. In a library so that the fuzz tests (tests/tests/fuzz/inputs.rs)
//! call it in-process.

use crate::recording::{damaged_chunk, messages};
use anyhow::{Context, Result, bail};
use serde_json::{Value, json};
use std::collections::BTreeMap;

/// A channel's line: topic, schema, encoding, messages.
type ChannelRow = (String, String, String, u64);

/// The recording's facts as JSON (`caravan info --json`): whether it has a summary, its
/// messages, time span, channels, metadata and attachments; an error for a file that is
/// damaged, cut short or not MCAP.
pub fn describe(bytes: &[u8]) -> Result<Value> {
    caravan_report::guarded("the file", || describe_unguarded(bytes))
}

fn describe_unguarded(bytes: &[u8]) -> Result<Value> {
    // A file cut short has no footer; it is read through up to where it ends.
    let summary = mcap::Summary::read(bytes).ok().flatten();
    let mut rows: BTreeMap<u16, ChannelRow> = BTreeMap::new();
    let (mut start, mut end, mut indexed) = (u64::MAX, 0, false);
    let mut metadata = BTreeMap::new();
    let mut attachments = Vec::new();
    match &summary {
        Some(s) if s.stats.is_some() => {
            indexed = true;
            let stats = s.stats.as_ref().expect("checked");
            (start, end) = (stats.message_start_time, stats.message_end_time);
            for (id, c) in &s.channels {
                let schema = c
                    .schema
                    .as_ref()
                    .map(|s| s.name.clone())
                    .unwrap_or_default();
                let count = stats.channel_message_counts.get(id).copied().unwrap_or(0);
                rows.insert(
                    *id,
                    (c.topic.clone(), schema, c.message_encoding.clone(), count),
                );
            }
            for index in &s.metadata_indexes {
                // An index past the file panics in the mcap crate: `guarded` makes it an error.
                let m = mcap::read::metadata(bytes, index)?;
                metadata.insert(m.name, m.metadata);
            }
            for index in &s.attachment_indexes {
                attachments.push(json!({"name": index.name, "media_type": index.media_type,
                                        "bytes": index.data_size}));
            }
        }
        _ => {
            for m in messages(bytes)? {
                let m =
                    m.map_err(|e| damaged(bytes, e, "the file ends in the middle of a record"))?;
                let c = &m.channel;
                let schema = c
                    .schema
                    .as_ref()
                    .map(|s| s.name.clone())
                    .unwrap_or_default();
                let row = rows
                    .entry(c.id)
                    .or_insert_with(|| (c.topic.clone(), schema, c.message_encoding.clone(), 0));
                row.3 += 1;
                start = start.min(m.log_time);
                end = end.max(m.log_time);
            }
        }
    }
    if rows.is_empty() {
        start = 0;
    }
    // A damaged summary may claim counts whose sum does not fit: that is bad input, not a panic.
    let total = rows
        .values()
        .try_fold(0u64, |sum, r| sum.checked_add(r.3))
        .context("the summary's message counts overflow: the file is damaged")?;
    if indexed {
        let mut read = 0u64;
        for m in messages(bytes)? {
            m.map_err(|e| damaged(bytes, e, "a chunk is damaged"))?;
            read += 1;
        }
        if read != total {
            bail!("the summary counts {total} messages but the file holds {read}");
        }
    }
    let mut channels: Vec<&ChannelRow> = rows.values().collect();
    channels.sort();
    Ok(json!({
        "indexed": indexed,
        "messages": total,
        "start_ns": start,
        "end_ns": end,
        "duration_s": end.saturating_sub(start) as f64 / 1e9,
        "channels": channels.iter().map(|(topic, schema, encoding, messages)| json!({
            "topic": topic, "schema": schema, "encoding": encoding, "messages": messages,
        })).collect::<Vec<_>>(),
        "metadata": metadata,
        "attachments": attachments,
    }))
}

/// A reader's `error` on `bytes`, naming the chunk that is damaged when one is (its number,
/// bytes and log times), else said as `otherwise`.
fn damaged(bytes: &[u8], error: mcap::McapError, otherwise: &'static str) -> anyhow::Error {
    match damaged_chunk(bytes) {
        Some(chunk) => anyhow::anyhow!("{chunk}"),
        None => anyhow::Error::new(error).context(otherwise),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn an_empty_recording_has_no_channels_and_a_truncated_one_is_an_error() {
        let mut file = std::io::Cursor::new(Vec::new());
        let mut w = mcap::Writer::new(&mut file).unwrap();
        let schema = w
            .add_schema("caravan::Pose2D", "jsonschema", b"{}")
            .unwrap();
        let ch = w
            .add_channel(schema, "robot/0/pose", "json", &Default::default())
            .unwrap();
        let header = |seq, t| mcap::records::MessageHeader {
            channel_id: ch,
            sequence: seq,
            log_time: t,
            publish_time: t,
        };
        w.write_to_known_channel(&header(1, 1_000_000_000), b"{}")
            .unwrap();
        w.write_to_known_channel(&header(2, 3_000_000_000), b"{}")
            .unwrap();
        w.finish().unwrap();
        drop(w);
        let bytes = file.into_inner();
        let facts = super::describe(&bytes).unwrap();
        assert_eq!(facts["messages"], 2);
        assert_eq!(facts["duration_s"], 2.0);
        assert_eq!(facts["channels"][0]["topic"], "robot/0/pose");
        assert_eq!(facts["indexed"], true);
        assert!(super::describe(&bytes[..bytes.len() / 2]).is_err());
    }

    /// Bytes overwritten inside a chunk: the summary still reads, the chunk's CRC does not,
    /// and the error names that chunk (the last of several).
    #[test]
    fn a_damaged_chunk_is_an_error_though_the_summary_reads() {
        let mut file = std::io::Cursor::new(Vec::new());
        let options = mcap::WriteOptions::new()
            .compression(None)
            .chunk_size(Some(200));
        let mut w = options.create(&mut file).unwrap();
        let schema = w
            .add_schema("caravan::Pose2D", "jsonschema", b"{}")
            .unwrap();
        let ch = (w.add_channel(schema, "robot/0/pose", "json", &Default::default())).unwrap();
        let payload = br#"{"x": 1.0, "y": 2.0, "theta": 0.5}"#;
        for seq in 0..10 {
            let header = mcap::records::MessageHeader {
                channel_id: ch,
                sequence: seq,
                log_time: u64::from(seq) * 1_000_000,
                publish_time: 0,
            };
            w.write_to_known_channel(&header, payload).unwrap();
        }
        w.finish().unwrap();
        drop(w);
        let mut bytes = file.into_inner();
        assert!(super::describe(&bytes).is_ok());
        let chunks = (mcap::Summary::read(&bytes).unwrap().unwrap().chunk_indexes).len();
        assert!(chunks > 1, "{chunks} chunk(s)");
        let at = (bytes.windows(payload.len()))
            .rposition(|w| w == payload)
            .unwrap();
        bytes[at + 3] = b'9';
        let err = format!("{:#}", super::describe(&bytes).unwrap_err());
        let named = format!("chunk {chunks} of {chunks} (bytes ");
        assert!(err.starts_with(&named), "{err}");
        assert!(
            err.contains("log times 0.006 to 0.009 s) is damaged: Chunk CRC failed"),
            "{err}"
        );
    }

    /// Found by the recording fuzz (tests/tests/fuzz/inputs.rs): a record's length near 2⁶⁴
    /// made `mcap::MessageStream` overflow (a panic), one of 2⁴⁰ inside a chunk made it
    /// allocate a terabyte (an abort), and one a little past its uncompressed chunk's end made
    /// mcap's reader overflow (a panic). All are errors now.
    #[test]
    fn a_hostile_record_length_is_an_error() {
        let mut file = std::io::Cursor::new(Vec::new());
        let options = mcap::WriteOptions::new().compression(None);
        let mut w = options.create(&mut file).unwrap();
        let schema = w
            .add_schema("caravan::Pose2D", "jsonschema", b"{}")
            .unwrap();
        let ch = (w.add_channel(schema, "robot/0/pose", "json", &Default::default())).unwrap();
        for seq in 0..3 {
            let header = mcap::records::MessageHeader {
                channel_id: ch,
                sequence: seq,
                log_time: u64::from(seq),
                publish_time: 0,
            };
            w.write_to_known_channel(&header, b"{}").unwrap();
        }
        w.finish().unwrap();
        drop(w);
        let bytes = file.into_inner();
        assert!(super::describe(&bytes).is_ok());
        // The header record, right after the magic.
        let header = 8;
        // The first record inside the first chunk (uncompressed: 40 bytes of chunk fields).
        let chunk = header + 9 + u64::from_le_bytes(bytes[9..17].try_into().unwrap()) as usize;
        assert_eq!(bytes[chunk], 0x06);
        let inner = chunk + 9 + 40;
        // A length a little past the chunk's end: mcap's reader subtracted it unchecked.
        let records = u64::from_le_bytes(bytes[chunk + 9 + 32..inner].try_into().unwrap());
        for (at, length) in [
            (header, u64::MAX),
            (header, 1 << 40),
            (inner, 1 << 40),
            (inner, u64::MAX),
            (inner, records),
        ] {
            let mut hostile = bytes.clone();
            hostile[at + 1..at + 9].copy_from_slice(&length.to_le_bytes());
            assert!(super::describe(&hostile).is_err(), "{at}: {length}");
            // Read through, as a file without a summary is.
            hostile.truncate(hostile.len() - 8);
            assert!(super::describe(&hostile).is_err(), "{at}: {length}");
        }
    }
}
