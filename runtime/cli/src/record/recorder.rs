//! The group recorder: taps the topics matching the record patterns and writes them to MCAP.
//!
//! In lockstep the launcher drains it after every advance of simulated time and messages are
//! written sorted by (stamp, topic, source, sequence) with log time = stamp and no wall-clock
//! fields, so reruns give byte-identical files. Wall-clock latency (send → tap) goes to the
//! topic statistics instead. Node statuses are tapped too but kept out of the MCAP: their
//! compute-time fields are wall-clock measurements.
//!
//! Every recorded topic gets its channel when it is discovered, before its first message, so
//! "nothing happened" (a channel without messages) differs from "not recorded" (no channel).
//! Beside each raw channel the recorder writes Foxglove's well-known views of it ([`scene`]).
//! The file has a summary (schemas, channels, statistics, chunk indexes) in both clock modes:
//! the writer lists them in id order and ids follow the deterministic order of discovery.

use super::{scene, schema};
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

/// What a recording says about its run: a `run` metadata record (seed, arguments, Caravan's
/// version; the wall-clock start only in realtime, where reruns differ anyway) and the resolved
/// launch file as the `launch.toml` attachment.
#[derive(Default)]
pub struct RecordingMeta {
    pub metadata: BTreeMap<String, String>,
    pub launch_file: Option<Vec<u8>>,
}

/// The `run` metadata: Caravan's version, the command line, the seed and (realtime only) the
/// wall-clock start in Unix ns.
pub fn run_metadata(seed: Option<u64>, wall_start_ns: Option<u64>) -> BTreeMap<String, String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut m = BTreeMap::from([
        (
            "caravan_version".to_string(),
            env!("CARGO_PKG_VERSION").to_string(),
        ),
        (
            "arguments".to_string(),
            shlex::try_join(args.iter().map(String::as_str)).unwrap_or_else(|_| args.join(" ")),
        ),
    ]);
    if let Some(seed) = seed {
        m.insert("seed".into(), seed.to_string());
    }
    if let Some(ns) = wall_start_ns {
        m.insert("wall_clock_start_ns".into(), ns.to_string());
    }
    m
}

type McapWriter = mcap::Writer<BufWriter<File>>;

/// Gives up a writer after a failed write. The mcap crate's writer cannot finish then (its
/// `finish`, which its `drop` calls, panics on the broken state), so it is never dropped: its
/// file closes when the process exits.
fn abandon(writer: McapWriter) {
    std::mem::forget(writer);
}

fn cannot_write(path: &Path) -> String {
    format!("cannot write the recording {}", path.display())
}

/// Applies `op` to the writer; on failure abandons it and says which file could not be written.
fn with_writer<T>(
    writer: &mut Option<McapWriter>,
    path: &Path,
    op: impl FnOnce(&mut McapWriter) -> mcap::McapResult<T>,
) -> Result<T> {
    let cannot = || cannot_write(path);
    let w = writer
        .as_mut()
        .ok_or_else(|| anyhow::anyhow!("an earlier write failed"))
        .with_context(cannot)?;
    op(w)
        .inspect_err(|_| {
            if let Some(w) = writer.take() {
                abandon(w);
            }
        })
        .with_context(cannot)
}

/// The modification time of the directory iceoryx2 keeps the services' static configs in,
/// which changes whenever a service is made or removed; `None` when it cannot be read.
fn services_changed(config: &iceoryx2::config::Config) -> Option<std::time::SystemTime> {
    let dir = Path::new(&config.global.root_path().to_string())
        .join(config.global.service.directory.to_string());
    std::fs::metadata(dir).and_then(|m| m.modified()).ok()
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
    /// When the group's services last changed as of the last complete discovery (the
    /// modification time of iceoryx2's service directory): discovery lists services only
    /// after a change, so an idle group costs no listing every second.
    services_changed: Option<std::time::SystemTime>,
    /// `None` once a write failed (a full disk): see [`abandon`].
    writer: Option<McapWriter>,
    /// The MCAP file, for messages about it (a full disk).
    path: std::path::PathBuf,
    channels: BTreeMap<String, u16>,
    /// Schema ids by name.
    schemas: BTreeMap<String, u16>,
    sequences: BTreeMap<u16, u32>,
    stats: BTreeMap<String, TopicStats>,
    node_status: BTreeMap<String, Value>,
    status_series: BTreeMap<String, Vec<(u64, u64)>>,
    /// When each running node's status last arrived (wall clock).
    status_heard: BTreeMap<String, std::time::Instant>,
    buffer: Vec<(usize, Tapped)>,
    /// The live view, which gets every topic; the file gets those the patterns match.
    live: Option<super::live::LiveView>,
}

impl Recorder {
    pub fn create(
        config: &iceoryx2::config::Config,
        path: &Path,
        patterns: &[String],
        lockstep: bool,
        meta: &RecordingMeta,
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
            // Multi-threaded compression need not give the same bytes on another machine.
            options = options.compression_threads(0);
        }
        let writer = options.create(BufWriter::new(file));
        let mut writer = Some(writer.with_context(|| cannot_write(path))?);
        if !meta.metadata.is_empty() {
            let record = mcap::records::Metadata {
                name: "run".into(),
                metadata: meta.metadata.clone(),
            };
            with_writer(&mut writer, path, |w| w.write_metadata(&record))?;
        }
        if let Some(launch) = &meta.launch_file {
            let attachment = mcap::Attachment {
                log_time: 0,
                create_time: 0,
                name: caravan_report::RESOLVED_LAUNCH_FILE.into(),
                media_type: "application/toml".into(),
                data: std::borrow::Cow::Borrowed(launch),
            };
            with_writer(&mut writer, path, |w| w.attach(&attachment))?;
        }
        Ok(Self {
            iox,
            config: config.clone(),
            patterns: patterns.to_vec(),
            lockstep,
            taps: Vec::new(),
            status_tap: None,
            seen: BTreeSet::new(),
            services_changed: None,
            writer,
            path: path.to_path_buf(),
            channels: BTreeMap::new(),
            schemas: BTreeMap::new(),
            sequences: BTreeMap::new(),
            stats: BTreeMap::new(),
            node_status: BTreeMap::new(),
            status_series: BTreeMap::new(),
            status_heard: BTreeMap::new(),
            buffer: Vec::new(),
            live: None,
        })
    }

    /// Serves every topic of the group to `live` as well (from the next discovery on).
    pub fn serve(&mut self, live: super::live::LiveView) {
        self.live = Some(live);
    }

    /// Whether `topic` goes into the file.
    fn is_recorded(&self, topic: &str) -> bool {
        self.patterns.iter().any(|p| glob_match(p, topic))
    }

    /// Whether any of `published` (topic hashes) was never looked at by discovery.
    pub fn has_unseen(&self, published: &[u64]) -> bool {
        published.iter().any(|h| !self.seen.contains(h))
    }

    /// Opens taps on new topics that match the patterns, and on `status`.
    pub fn discover(&mut self) -> Result<()> {
        // Read before listing: a service made while listing changes it again.
        let changed = services_changed(&self.config);
        if changed.is_some() && changed == self.services_changed {
            return Ok(());
        }
        let mut complete = true;
        let status = caravan_schemas::topics::status();
        let mut opened = Vec::new();
        for info in list_topics(&self.config, false)? {
            let hash = caravan_schemas::lockstep::name_hash(&info.name);
            if !self.seen.insert(hash) {
                continue;
            }
            let wanted =
                info.name == status.name() || self.live.is_some() || self.is_recorded(&info.name);
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
                Ok(tap) if info.name == status.name() => {
                    // Served live (wall-clock measurements are fine there), never recorded.
                    if let Some(live) = &mut self.live {
                        live.advertise_raw(status.name(), tap.type_name(), true)?;
                    }
                    self.status_tap = Some(tap)
                }
                Ok(tap) => {
                    opened.push((tap.topic().to_string(), tap.type_name()));
                    self.taps.push(tap);
                }
                // The service went away between listing and opening (its last node exited),
                // or is still being made; look again next time.
                Err(_) => {
                    self.seen.remove(&hash);
                    complete = false;
                }
            }
        }
        if complete {
            self.services_changed = changed;
        }
        self.taps.sort_by(|a, b| a.topic().cmp(b.topic()));
        // Listing order is the file system's; channel ids follow the topics' names.
        opened.sort();
        for (topic, type_name) in opened {
            let recorded = self.is_recorded(&topic);
            if recorded {
                self.channel(&topic, type_name)?;
            }
            for (view, schema) in scene::topics_of(&topic, type_name) {
                if recorded {
                    self.scene_channel(&view, schema)?;
                }
                if let Some(live) = &mut self.live {
                    live.advertise_view(&view, schema())?;
                }
            }
            if let Some(live) = &mut self.live {
                live.advertise_raw(&topic, type_name, !self.lockstep)?;
            }
        }
        Ok(())
    }

    fn schema_id(&mut self, name: &str, encoding: &str, data: &[u8]) -> Result<u16> {
        if let Some(&id) = self.schemas.get(name) {
            return Ok(id);
        }
        let id = with_writer(&mut self.writer, &self.path, |w| {
            w.add_schema(name, encoding, data)
        })?;
        self.schemas.insert(name.to_string(), id);
        Ok(id)
    }

    /// The raw channel of `topic`, added at discovery.
    fn channel(&mut self, topic: &str, type_name: &str) -> Result<u16> {
        if let Some(&id) = self.channels.get(topic) {
            return Ok(id);
        }
        let schema = schema::for_type(type_name, !self.lockstep).unwrap_or(json!({}));
        let schema_id = self.schema_id(type_name, "jsonschema", schema.to_string().as_bytes())?;
        self.add_channel(topic, schema_id, "json")
    }

    /// A Foxglove view's channel, added on first use.
    fn scene_channel(&mut self, topic: &str, schema: fn() -> scene::SceneSchema) -> Result<u16> {
        if let Some(&id) = self.channels.get(topic) {
            return Ok(id);
        }
        let s = schema();
        let schema_id = self.schema_id(&s.name, &s.encoding, &s.data)?;
        self.add_channel(topic, schema_id, &s.encoding)
    }

    fn add_channel(&mut self, topic: &str, schema_id: u16, encoding: &str) -> Result<u16> {
        let id = with_writer(&mut self.writer, &self.path, |w| {
            w.add_channel(schema_id, topic, encoding, &BTreeMap::new())
        })?;
        self.channels.insert(topic.to_string(), id);
        Ok(id)
    }

    fn write_message(&mut self, channel: u16, stamp_ns: u64, data: &[u8]) -> Result<()> {
        let sequence = self.sequences.entry(channel).or_insert(0);
        *sequence += 1;
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: *sequence,
            log_time: stamp_ns,
            publish_time: stamp_ns,
        };
        with_writer(&mut self.writer, &self.path, |w| {
            w.write_to_known_channel(&header, data)
        })
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
                if let Some(live) = &mut self.live {
                    let mut record = m.json.clone();
                    record["header"] = schema::header_json(&m.header, true);
                    live.log(
                        tap.topic(),
                        m.header.stamp_ns,
                        &serde_json::to_vec(&record)?,
                    );
                }
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
        let stamp_ns = msg.header.stamp_ns;
        let views = scene::views(&topic, type_name, &msg.json, stamp_ns);
        let mut record = msg.json;
        if let Value::Object(fields) = &mut record {
            let header = schema::header_json(&msg.header, !self.lockstep);
            fields.insert("header".into(), header);
        }
        let bytes = serde_json::to_vec(&record)?;
        if let Some(live) = &mut self.live {
            live.log(&topic, stamp_ns, &bytes);
            for view in &views {
                live.log(&view.topic, stamp_ns, &view.bytes);
            }
        }
        // Discovery gave every recorded topic its channel; the others are served live only.
        let Some(&channel) = self.channels.get(&topic) else {
            return Ok(());
        };
        self.write_message(channel, stamp_ns, &bytes)?;
        for view in views {
            let channel = self.scene_channel(&view.topic, view.schema)?;
            self.write_message(channel, stamp_ns, &view.bytes)?;
        }
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

    /// Whether node `name` has published a status.
    pub fn has_reported(&self, name: &str) -> bool {
        self.status_heard.contains_key(name)
    }

    /// Running nodes whose once-a-second status has not arrived for `timeout`: in realtime a
    /// node whose step never returns stops publishing it.
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
        with_writer(&mut self.writer, &self.path, |w| w.finish().map(|_| ()))?;
        if let Some(w) = self.writer.take() {
            // The last bytes leave the buffer here; a full disk must not pass unseen.
            use std::io::Write;
            w.into_inner()
                .flush()
                .with_context(|| cannot_write(&self.path))?;
        }
        Ok(Recording {
            topics: self.stats,
            node_status: self.node_status,
            status_series: self.status_series,
        })
    }
}
