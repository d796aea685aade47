//! The group recorder: taps the topics matching the record patterns and writes them to MCAP.
//!
//! In lockstep the launcher drains it after every advance of simulated time and messages are
//! written sorted by (stamp, topic, source, sequence) with log time = stamp and no wall-clock
//! fields, so reruns give byte-identical files. Wall-clock latency (send → tap) goes to the
//! topic statistics instead. Node statuses are tapped too but kept out of the MCAP: their
//! compute-time fields are wall-clock measurements.

use super::schema;
use crate::launch::model::glob_match;
use anyhow::{Context, Result};
use caravan::tap::{DynTap, Tapped, list_topics, open_tap};
use hdrhistogram::Histogram;
use iceoryx2::prelude::*;
use serde_json::{Value, json};
use std::collections::{BTreeMap, BTreeSet};
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

/// Per-topic statistics seen by the recorder.
pub struct TopicStats {
    pub type_name: String,
    pub messages: u64,
    pub missed: u64,
    /// Wall-clock latency from send to the recorder's tap, ns.
    pub latency: Histogram<u64>,
}

/// What a finished recording leaves for the report.
pub struct Recording {
    pub topics: BTreeMap<String, TopicStats>,
    /// Last status of each node, as JSON, by node name.
    pub node_status: BTreeMap<String, Value>,
    /// Each node's running statuses in order, as (resident KiB, deadline misses so far).
    pub status_series: BTreeMap<String, Vec<(u64, u64)>>,
}

pub struct Recorder {
    iox: iceoryx2::node::Node<ipc::Service>,
    config: iceoryx2::config::Config,
    patterns: Vec<String>,
    lockstep: bool,
    taps: Vec<Box<dyn DynTap>>,
    status_tap: Option<Box<dyn DynTap>>,
    /// Topic hashes discovery already looked at, recorded or not.
    seen: BTreeSet<u64>,
    writer: mcap::Writer<BufWriter<File>>,
    /// The MCAP file, for messages about it (a full disk).
    path: std::path::PathBuf,
    channels: BTreeMap<String, u16>,
    sequences: BTreeMap<u16, u32>,
    stats: BTreeMap<String, TopicStats>,
    node_status: BTreeMap<String, Value>,
    status_series: BTreeMap<String, Vec<(u64, u64)>>,
    /// When each running node's status last arrived (wall clock).
    status_heard: BTreeMap<String, std::time::Instant>,
    buffer: Vec<(usize, Tapped)>,
}

impl Recorder {
    pub fn create(
        config: &iceoryx2::config::Config,
        path: &Path,
        patterns: &[String],
        lockstep: bool,
    ) -> Result<Self> {
        let iox = NodeBuilder::new()
            .config(config)
            .signal_handling_mode(SignalHandlingMode::Disabled)
            .create::<ipc::Service>()
            .map_err(|e| anyhow::anyhow!("recorder node: {e:?}"))?;
        let file =
            File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
        let mut options = mcap::WriteOptions::new().library("caravan");
        if lockstep {
            // The crate writes summary channels and schemas in hash order. Leave them out so
            // that reruns are byte-identical (they stay in the data section), and the chunk
            // indexes with them: readers that find indexes expect summary channels, and
            // without indexes they read the file linearly.
            options = options
                .repeat_channels(false)
                .repeat_schemas(false)
                .emit_chunk_indexes(false);
        }
        let writer = options
            .create(BufWriter::new(file))
            .context("cannot start the MCAP file")?;
        Ok(Self {
            iox,
            config: config.clone(),
            patterns: patterns.to_vec(),
            lockstep,
            taps: Vec::new(),
            status_tap: None,
            seen: BTreeSet::new(),
            writer,
            path: path.to_path_buf(),
            channels: BTreeMap::new(),
            sequences: BTreeMap::new(),
            stats: BTreeMap::new(),
            node_status: BTreeMap::new(),
            status_series: BTreeMap::new(),
            status_heard: BTreeMap::new(),
            buffer: Vec::new(),
        })
    }

    fn cannot_write(&self) -> String {
        format!("cannot write the recording {}", self.path.display())
    }

    /// Whether any of `published` (topic hashes) was never looked at by discovery.
    pub fn has_unseen(&self, published: &[u64]) -> bool {
        published.iter().any(|h| !self.seen.contains(h))
    }

    /// Opens taps on new topics that match the patterns, and on `status`.
    pub fn discover(&mut self) -> Result<()> {
        let status = caravan_schemas::topics::status();
        for info in list_topics(&self.config, false)? {
            let hash = caravan_schemas::lockstep::name_hash(&info.name);
            if !self.seen.insert(hash) {
                continue;
            }
            let wanted = info.name == status.name()
                || self.patterns.iter().any(|p| glob_match(p, &info.name));
            if !wanted {
                continue;
            }
            if caravan_schemas::with_message_type!(&info.type_name, |T| ()).is_none() {
                // A type outside the schemas (a user's own) cannot be decoded; say so once.
                eprintln!(
                    "caravan: not recording '{}': unknown message type '{}'",
                    info.name, info.type_name
                );
                continue;
            }
            match open_tap(&self.iox, &info.name, &info.type_name) {
                Ok(tap) if info.name == status.name() => self.status_tap = Some(tap),
                Ok(tap) => self.taps.push(tap),
                // The service went away between listing and opening (its last node exited);
                // look again next time.
                Err(_) => {
                    self.seen.remove(&hash);
                }
            }
        }
        self.taps.sort_by(|a, b| a.topic().cmp(b.topic()));
        Ok(())
    }

    pub fn taps(&self) -> impl Iterator<Item = &dyn DynTap> {
        self.taps
            .iter()
            .map(|t| t.as_ref())
            .chain(self.status_tap.as_deref())
    }

    /// Reads every waiting message and writes it.
    pub fn drain(&mut self) -> Result<()> {
        let now_wall = caravan::wall_clock_ns();
        let mut batch = Vec::new();
        for (i, tap) in self.taps.iter().enumerate() {
            tap.drain(&mut batch)?;
            self.buffer.extend(batch.drain(..).map(|m| (i, m)));
        }
        if let Some(tap) = &self.status_tap {
            tap.drain(&mut batch)?;
            for m in batch.drain(..) {
                let Some(node) = m
                    .json
                    .get("node")
                    .and_then(Value::as_str)
                    .map(str::to_string)
                else {
                    continue;
                };
                if m.json["running"] == 1 {
                    self.status_heard
                        .insert(node.clone(), std::time::Instant::now());
                    let field = |k: &str| m.json[k].as_u64().unwrap_or(0);
                    self.status_series
                        .entry(node.clone())
                        .or_default()
                        .push((field("rss_kib"), field("deadline_misses")));
                } else {
                    self.status_heard.remove(&node);
                }
                self.node_status.insert(node, m.json);
            }
        }
        let mut buffer = std::mem::take(&mut self.buffer);
        buffer.sort_by_key(|(i, m)| (m.header.stamp_ns, *i, m.header.source_id, m.header.seq));
        for (i, msg) in buffer.drain(..) {
            self.write(i, msg, now_wall)?;
        }
        self.buffer = buffer;
        Ok(())
    }

    fn write(&mut self, tap_index: usize, msg: Tapped, now_wall: u64) -> Result<()> {
        let tap = &self.taps[tap_index];
        let topic = tap.topic().to_string();
        let type_name = tap.type_name();
        let channel = match self.channels.get(&topic) {
            Some(&id) => id,
            None => {
                let schema = schema::for_type(type_name, !self.lockstep).unwrap_or(json!({}));
                let schema_id =
                    self.writer
                        .add_schema(type_name, "jsonschema", schema.to_string().as_bytes());
                let schema_id = schema_id.with_context(|| self.cannot_write())?;
                let id = self
                    .writer
                    .add_channel(schema_id, &topic, "json", &BTreeMap::new());
                let id = id.with_context(|| self.cannot_write())?;
                self.channels.insert(topic.clone(), id);
                id
            }
        };
        let mut header = json!({"seq": msg.header.seq, "stamp_ns": msg.header.stamp_ns, "source_id": msg.header.source_id});
        if !self.lockstep {
            header["send_wall_ns"] = json!(msg.header.send_wall_ns);
        }
        let mut record = msg.json;
        if let Value::Object(fields) = &mut record {
            fields.insert("header".into(), header);
        }
        let sequence = self.sequences.entry(channel).or_insert(0);
        *sequence += 1;
        let written = self.writer.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id: channel,
                sequence: *sequence,
                log_time: msg.header.stamp_ns,
                publish_time: msg.header.stamp_ns,
            },
            &serde_json::to_vec(&record)?,
        );
        written.with_context(|| self.cannot_write())?;
        let stats = self.stats.entry(topic).or_insert_with(|| TopicStats {
            type_name: type_name.to_string(),
            messages: 0,
            missed: 0,
            latency: Histogram::new_with_bounds(1, 3_600_000_000_000, 3).expect("valid bounds"),
        });
        stats.messages += 1;
        stats
            .latency
            .saturating_record(now_wall.saturating_sub(msg.header.send_wall_ns).max(1));
        Ok(())
    }

    /// Running nodes whose once-a-second status has not arrived for `timeout`: in realtime a
    /// node whose step never returns stops publishing it.
    /// Whether node `name` has published a status.
    pub fn has_reported(&self, name: &str) -> bool {
        self.status_heard.contains_key(name)
    }

    pub fn silent_nodes(&self, timeout: std::time::Duration) -> Vec<String> {
        self.status_heard
            .iter()
            .filter(|(_, t)| t.elapsed() > timeout)
            .map(|(n, _)| n.clone())
            .collect()
    }

    pub fn finish(mut self) -> Result<Recording> {
        self.drain()?;
        for tap in &self.taps {
            if let Some(s) = self.stats.get_mut(tap.topic()) {
                s.missed = tap.missed();
            }
        }
        self.writer.finish().with_context(|| self.cannot_write())?;
        Ok(Recording {
            topics: self.stats,
            node_status: self.node_status,
            status_series: self.status_series,
        })
    }
}
