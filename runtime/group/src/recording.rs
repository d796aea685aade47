//! A recording's Caravan messages as the player reads them, from a Caravan recording
//! (`play.rs`) or a rosbag2 bag (`bag.rs`).

use anyhow::{Context, Result};
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

/// Every message of the MCAP file `bytes`, in file order, each chunk's CRC checked as it is
/// decompressed. No record may be longer than the file or [`caravan::input::MAX_INPUT_BYTES`],
/// whichever is more, nor run past the end of its uncompressed chunk: a damaged length field
/// is an error, not an allocation of a terabyte or an overflow (`mcap::MessageStream` sets no
/// limit and panics on a length near 2⁶⁴; mcap 0.26's reader subtracts an uncompressed chunk's
/// record from what remains of the chunk unchecked). Found by the recording fuzz
/// (tests/tests/fuzz/inputs.rs).
pub(crate) fn messages(bytes: &[u8]) -> Result<mcap::io::MessageReader<std::io::Cursor<&[u8]>>> {
    records_fit_their_chunks(bytes)?;
    let limit = usize::try_from(caravan::input::MAX_INPUT_BYTES)
        .unwrap_or(usize::MAX)
        .max(bytes.len());
    let options = mcap::sans_io::LinearReaderOptions::default()
        .with_record_length_limit(limit)
        .with_validate_chunk_crcs(true);
    Ok(mcap::io::MessageReader::new_with_options(
        std::io::Cursor::new(bytes),
        options,
    ))
}

/// Checks that each record inside an uncompressed chunk ends within the chunk, walking the
/// file's records as mcap's reader does; what that reader refuses itself is left to it.
fn records_fit_their_chunks(bytes: &[u8]) -> Result<()> {
    const CHUNK: u8 = 0x06;
    const FOOTER: u8 = 0x02;
    let number = |at: usize, width: usize| -> Option<usize> {
        let mut le = [0u8; 8];
        le[..width].copy_from_slice(bytes.get(at..at.checked_add(width)?)?);
        usize::try_from(u64::from_le_bytes(le)).ok()
    };
    // Where a record of length field at `at + 1` ends, if before `end`.
    let record_end = |at: usize, end: usize| {
        number(at + 1, 8)
            .and_then(|len| (at + 9).checked_add(len))
            .filter(|&e| e <= end)
    };
    let mut at = 8;
    while let Some(end) = record_end(at, bytes.len()) {
        if bytes[at] == FOOTER {
            break;
        }
        // A chunk: start and end times, uncompressed size and CRC, the compression's name
        // (empty: uncompressed), the records' length, the records.
        let content = at + 9;
        let records = (bytes[at] == CHUNK && number(content + 28, 4) == Some(0))
            .then(|| number(content + 32, 8))
            .flatten()
            .and_then(|len| (content + 40).checked_add(len))
            .filter(|&e| e <= end);
        if let Some(records_end) = records {
            let mut r = content + 40;
            while r < records_end {
                r = record_end(r, records_end).with_context(|| {
                    format!("a record inside the chunk at byte {at} runs past the chunk's end")
                })?;
            }
        }
        at = end;
    }
    Ok(())
}

/// Which chunk of the MCAP file `bytes` is damaged, if one is: each top-level chunk is read
/// alone, decompressed and its CRC checked, and the first that fails is named by its number,
/// its bytes and its messages' log times, with what is wrong (`chunk 2 of 5 (bytes 4096 to
/// 8190, log times 1.000 to 2.000 s) is damaged: Chunk CRC failed (…)`). Used to say where a
/// reader's error is, which mcap's reader does not.
pub(crate) fn damaged_chunk(bytes: &[u8]) -> Option<String> {
    const CHUNK: u8 = 0x06;
    let chunks: Vec<_> = top_level_records(bytes)
        .into_iter()
        .filter(|r| bytes[r.start] == CHUNK)
        .collect();
    let count = chunks.len();
    chunks.into_iter().enumerate().find_map(|(i, r)| {
        let error = chunk_error(&bytes[r.clone()])?;
        let times = match mcap::read::parse_record(CHUNK, &bytes[r.start + 9..r.end]) {
            Ok(mcap::records::Record::Chunk { header, .. }) => format!(
                ", log times {:.3} to {:.3} s",
                header.message_start_time as f64 / 1e9,
                header.message_end_time as f64 / 1e9
            ),
            _ => String::new(),
        };
        Some(format!(
            "chunk {} of {count} (bytes {} to {}{times}) is damaged: {error}",
            i + 1,
            r.start,
            r.end - 1
        ))
    })
}

/// What is wrong with the one chunk record `record` (opcode, length and content), read as
/// mcap's reader reads a file's chunks, with its CRC checked; `None` when it reads whole.
fn chunk_error(record: &[u8]) -> Option<String> {
    let options = mcap::sans_io::LinearReaderOptions::default()
        .with_skip_start_magic(true)
        .with_skip_end_magic(true)
        .with_record_length_limit(record.len())
        .with_validate_chunk_crcs(true);
    let mut reader = mcap::sans_io::LinearReader::new_with_options(options);
    let mut rest = record;
    while let Some(event) = reader.next_event() {
        match event {
            Ok(mcap::sans_io::LinearReadEvent::ReadRequest(need)) => {
                let n = need.min(rest.len());
                reader.insert(n).copy_from_slice(&rest[..n]);
                reader.notify_read(n);
                rest = &rest[n..];
            }
            Ok(mcap::sans_io::LinearReadEvent::Record { .. }) => {}
            Err(e) => return Some(e.to_string()),
        }
    }
    None
}

/// The byte ranges of the file's top-level records (opcode, length and content), up to the
/// footer or the first whose length does not fit the file.
fn top_level_records(bytes: &[u8]) -> Vec<std::ops::Range<usize>> {
    let mut records = Vec::new();
    let mut at = 8;
    while let Some(len) = bytes
        .get(at + 1..at + 9)
        .map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")))
    {
        let Some(end) = usize::try_from(len)
            .ok()
            .and_then(|len| (at + 9).checked_add(len))
            .filter(|&e| e <= bytes.len())
        else {
            break;
        };
        records.push(at..end);
        if bytes[at] == 0x02 {
            break;
        }
        at = end;
    }
    records
}

/// Whether `patterns` (names or patterns with `*`, as in a launch file's `record`) select
/// `topic`; no patterns select every topic.
pub(crate) fn selected(patterns: &[String], topic: &str) -> bool {
    patterns.is_empty()
        || patterns
            .iter()
            .any(|p| caravan_launch::model::glob_match(p, topic))
}
