//! `caravan info FILE.mcap`: what a recording holds, from its summary (as `ros2 bag info` and
//! `mcap info` print): time span, messages, channels with schema and count, the run's metadata
//! and attachments. A file without a summary (cut short by a crash) is read through instead.
//!
//! Either way every message is read once, with each chunk's CRC checked, and the count must
//! match the summary's: a damaged file is refused (exit 2), as `play` and `resim` refuse it,
//! rather than described from a summary that no longer holds.

use anyhow::{Context, Result, bail};
use clap::Args;
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::path::PathBuf;

#[derive(Args)]
pub struct InfoArgs {
    /// The recording (a run directory's record.mcap)
    pub file: PathBuf,
    /// Print JSON instead of a table
    #[arg(long)]
    pub json: bool,
}

/// A channel's line: topic, schema, encoding, messages.
type ChannelRow = (String, String, String, u64);

/// The recording's facts as JSON.
pub fn describe(bytes: &[u8]) -> Result<Value> {
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
                let m = m.context("the file ends in the middle of a record")?;
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
    let total: u64 = rows.values().map(|r| r.3).sum();
    if indexed {
        let mut read = 0u64;
        for m in messages(bytes)? {
            m.context("a chunk is damaged")?;
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

/// Every message, each chunk's CRC checked as it is decompressed.
fn messages(bytes: &[u8]) -> Result<mcap::MessageStream<'_>> {
    Ok(mcap::MessageStream::new_with_options(
        bytes,
        mcap::read::Options::ValidateChunkCrcs.into(),
    )?)
}

/// Prints what the recording holds; returns the exit code (2: the file cannot be read, is
/// not MCAP, or is damaged).
pub fn info(args: &InfoArgs) -> Result<u8> {
    let file = args.file.display();
    let bytes = match caravan::input::map_recording(&args.file) {
        Ok(b) => b,
        Err(e) => return Ok(refuse(format!("cannot read {file}: {e:#}"))),
    };
    if !bytes.starts_with(mcap::MAGIC) {
        return Ok(refuse(format!("{file} is not an MCAP file")));
    }
    let facts = match describe(&bytes) {
        Ok(f) => f,
        Err(e) => return Ok(refuse(format!("{file}: {e:#}"))),
    };
    if args.json {
        println!("{facts:#}");
        return Ok(0);
    }
    println!("file:        {}", args.file.display());
    println!(
        "messages:    {} in {:.3} s{}",
        facts["messages"],
        facts["duration_s"].as_f64().unwrap_or(0.0),
        if facts["indexed"] == true {
            ""
        } else {
            " (no summary: read through)"
        }
    );
    for (name, m) in facts["metadata"].as_object().into_iter().flatten() {
        let pairs: Vec<String> = m
            .as_object()
            .into_iter()
            .flatten()
            .map(|(k, v)| format!("{k}={}", v.as_str().unwrap_or_default()))
            .collect();
        println!("metadata:    {name}: {}", pairs.join(", "));
    }
    for a in facts["attachments"].as_array().into_iter().flatten() {
        println!(
            "attachment:  {} ({}, {} B)",
            a["name"].as_str().unwrap_or(""),
            a["media_type"].as_str().unwrap_or(""),
            a["bytes"]
        );
    }
    let channels = facts["channels"].as_array().cloned().unwrap_or_default();
    let width = channels
        .iter()
        .map(|c| c["topic"].as_str().unwrap_or("").len())
        .max()
        .unwrap_or(5)
        .max(5);
    println!("channels:    {}", channels.len());
    for c in &channels {
        println!(
            "  {:width$}  {:>8}  {} ({})",
            c["topic"].as_str().unwrap_or(""),
            c["messages"],
            c["schema"].as_str().unwrap_or(""),
            c["encoding"].as_str().unwrap_or(""),
        );
    }
    println!("verified:    every chunk's CRC, and the message count");
    Ok(0)
}

fn refuse(message: String) -> u8 {
    eprintln!("caravan: {message}");
    caravan_group::launch::EXIT_BAD_INPUT
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

    /// Bytes overwritten inside a chunk: the summary still reads, the chunk's CRC does not.
    #[test]
    fn a_damaged_chunk_is_an_error_though_the_summary_reads() {
        let mut file = std::io::Cursor::new(Vec::new());
        let options = mcap::WriteOptions::new().compression(None);
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
        let at = (bytes.windows(payload.len()))
            .position(|w| w == payload)
            .unwrap();
        bytes[at + 3] = b'9';
        let err = format!("{:#}", super::describe(&bytes).unwrap_err());
        assert!(err.contains("a chunk is damaged"), "{err}");
    }
}
