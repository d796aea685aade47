//! The group recorder: taps the topics matching the record patterns and writes them to MCAP.
//!
//! The taps live on the launcher's driver thread; the file is written on a thread of its own
//! ([`super::writer`]). In lockstep the launcher drains the taps after every advance of
//! simulated time and messages are written sorted by (stamp, topic, source, sequence) with log time = stamp and no wall-clock
//! fields, so reruns give byte-identical files. Wall-clock latency (send → tap) goes to the
//! topic statistics instead. Node statuses are tapped too but kept out of the MCAP: their
//! compute-time fields are wall-clock measurements.
//!
//! Every recorded topic gets its channel when it is discovered, before its first message, so
//! "nothing happened" (a channel without messages) differs from "not recorded" (no channel).
//! Beside each raw channel the recorder writes Foxglove's well-known views of it ([`super::scene`]).
//! The file has a summary (schemas, channels, statistics, chunk indexes) in both clock modes:
//! the writer lists them in id order and ids follow the deterministic order of discovery.

use super::schema;
use super::writer::{Command, Drained, NewTopic, WriterThread};
pub use super::writer::{RecordingMeta, TopicStats};
use anyhow::Result;
use caravan::discovery::services_changed;
use caravan::pattern::glob_match;
use caravan::tap::{DynTap, Tapped, list_topics, open_tap};
use iceoryx2::prelude::*;
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The lockstep hash of the nodes' status topic (`caravan_schemas::topics::status`).
const STATUS_HASH: u64 = caravan_schemas::lockstep::name_hash("status");

/// What a finished recording leaves for the report.
pub struct Recording {
    pub topics: BTreeMap<String, TopicStats>,
    /// Last status of each node, as JSON, by node name.
    pub node_status: BTreeMap<String, Value>,
    /// Each node's running statuses in order, as (resident KiB, deadline misses so far).
    pub status_series: BTreeMap<String, Vec<(u64, u64)>>,
}

/// This process's command line after the program, as a recording's `run` metadata keeps it:
/// which host's launcher records a group across hosts is not part of the run (the file is the
/// one a single host makes), so `--host NAME` is left out.
pub fn command_arguments() -> Vec<String> {
    let mut args = Vec::new();
    let mut all = std::env::args().skip(1);
    while let Some(arg) = all.next() {
        match arg.as_str() {
            "--host" => {
                all.next();
            }
            a if a.starts_with("--host=") => {}
            _ => args.push(arg),
        }
    }
    args
}

/// The `run` metadata: Caravan's version, the command line (`args`, see
/// [`command_arguments`]), the seed and (realtime only) the wall-clock start in Unix ns.
pub fn run_metadata(
    args: &[String],
    seed: Option<u64>,
    wall_start_ns: Option<u64>,
) -> BTreeMap<String, String> {
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

pub struct Recorder {
    iox: iceoryx2::node::Node<ipc::Service>,
    config: iceoryx2::config::Config,
    patterns: Vec<String>,
    /// Taps sorted by topic, each with its id (the order it was discovered in) and its
    /// topic's hash.
    taps: Vec<(usize, u64, Box<dyn DynTap>)>,
    status_tap: Option<Box<dyn DynTap>>,
    /// Topic hashes discovery already looked at, recorded or not.
    seen: BTreeSet<u64>,
    /// When the group's services last changed as of the last complete discovery (the
    /// modification time of iceoryx2's service directory): discovery lists services only
    /// after a change, so an idle group costs no listing every second.
    services_changed: Option<std::time::SystemTime>,
    /// Every topic is tapped for the live view, recorded or not.
    serving: bool,
    writer: WriterThread,
    node_status: BTreeMap<String, Value>,
    status_series: BTreeMap<String, Vec<(u64, u64)>>,
    /// When each running node's status last arrived (wall clock).
    status_heard: BTreeMap<String, std::time::Instant>,
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
        Ok(Self {
            iox,
            config: config.clone(),
            patterns: patterns.to_vec(),
            taps: Vec::new(),
            status_tap: None,
            seen: BTreeSet::new(),
            services_changed: None,
            serving: false,
            writer: WriterThread::start(path, lockstep, meta)?,
            node_status: BTreeMap::new(),
            status_series: BTreeMap::new(),
            status_heard: BTreeMap::new(),
        })
    }

    /// Serves every topic of the group to `live` as well (from the next discovery on).
    pub fn serve(&mut self, live: super::live::LiveView) -> Result<()> {
        self.serving = true;
        self.writer.send(Command::Serve(live))
    }

    /// Whether `topic` goes into the file.
    fn is_recorded(&self, topic: &str) -> bool {
        self.patterns.iter().any(|p| glob_match(p, topic))
    }

    /// Hashes of every topic discovery has looked at, recorded or not.
    pub fn seen(&self) -> impl Iterator<Item = u64> + '_ {
        self.seen.iter().copied()
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
            let wanted = info.name == status.name() || self.serving || self.is_recorded(&info.name);
            if !wanted {
                continue;
            }
            if let Err(e) = caravan::types::lookup(self.iox.config(), &info.type_name) {
                // Not published through Caravan (its type undescribed): say so once.
                eprintln!("caravan: not recording '{}': {e}", info.name);
                continue;
            }
            match open_tap(&self.iox, &info.name, &info.type_name) {
                Ok(tap) if info.name == status.name() => {
                    // Served live (wall-clock measurements are fine there), never recorded.
                    self.writer.send(Command::StatusTopic {
                        topic: status.name().to_string(),
                        descriptor: tap.descriptor().clone(),
                    })?;
                    self.status_tap = Some(tap)
                }
                Ok(tap) => opened.push(tap),
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
        // Listing order is the file system's; ids (and so channel ids) follow the names.
        opened.sort_by(|a, b| a.topic().cmp(b.topic()));
        let mut topics = Vec::new();
        for tap in opened {
            let id = self.taps.len();
            topics.push(NewTopic {
                id,
                topic: tap.topic().to_string(),
                type_name: tap.type_name(),
                descriptor: tap.descriptor().clone(),
                recorded: self.is_recorded(tap.topic()),
            });
            let hash = caravan_schemas::lockstep::name_hash(tap.topic());
            self.taps.push((id, hash, tap));
        }
        self.taps.sort_by(|a, b| a.2.topic().cmp(b.2.topic()));
        if !topics.is_empty() {
            self.writer.send(Command::Topics(topics))?;
        }
        Ok(())
    }

    pub fn taps(&self) -> impl Iterator<Item = &dyn DynTap> {
        self.taps
            .iter()
            .map(|(_, _, t)| t.as_ref())
            .chain(self.status_tap.as_deref())
    }

    /// Reads every waiting message and hands them to the writer.
    pub fn drain(&mut self) -> Result<()> {
        self.drain_except(&[], u64::MAX)
    }

    /// Reads every waiting message stamped up to `until_ns`, except on `later` topics
    /// (hashes), and hands them to the writer. In lockstep, `later` are the topics of nodes
    /// already stepping at the next time (`caravan_lockstep::Advance::overlapping`): nothing
    /// on them belongs to the time that ended, and they are drained once theirs ends, so each
    /// batch holds one time. A message stamped after `until_ns` (published ahead by a node
    /// granted several periods) waits in its tap until a drain reaches its time.
    pub fn drain_except(&mut self, later: &[u64], until_ns: u64) -> Result<()> {
        self.drain_taps(|hash| !later.contains(&hash), true, until_ns)
    }

    /// Like [`Self::drain_except`], but looks only at `published` (sorted hashes: the topics
    /// the nodes said they published at the time that ended, `caravan_lockstep::Advance`)
    /// and at taps holding messages of a later time: the others have nothing new, and asking
    /// each of dozens of taps at every advance was a good part of the launcher's work per
    /// tick.
    pub fn drain_published(
        &mut self,
        published: &[u64],
        later: &[u64],
        until_ns: u64,
    ) -> Result<()> {
        // A node publishes its status once a second: most advances have none.
        let status = published.binary_search(&STATUS_HASH).is_ok();
        self.drain_taps(
            |hash| published.binary_search(&hash).is_ok() && !later.contains(&hash),
            status,
            until_ns,
        )
    }

    fn drain_taps(
        &mut self,
        wanted: impl Fn(u64) -> bool,
        status: bool,
        until_ns: u64,
    ) -> Result<()> {
        let now_wall = caravan::wall_clock_ns();
        let mut batch = Vec::new();
        let mut messages = Vec::new();
        for (rank, (id, hash, tap)) in self.taps.iter().enumerate() {
            if !wanted(*hash) && !tap.holds() {
                continue;
            }
            tap.drain_until(until_ns, &mut batch)?;
            messages.extend(batch.drain(..).map(|message| Drained {
                rank,
                id: *id,
                message,
            }));
        }
        // Statuses are not recorded: the report and the hang watch want the newest.
        if let Some(tap) = self.status_tap.as_ref().filter(|_| status) {
            tap.drain(&mut batch)?;
        }
        for m in batch.drain(..) {
            self.note_status(m)?;
        }
        if !messages.is_empty() {
            self.writer.send(Command::Batch { messages, now_wall })?;
        }
        Ok(())
    }

    /// Keeps a node's status for the report and the hang watch, and serves it live.
    fn note_status(&mut self, m: Tapped) -> Result<()> {
        let mut json = m.json()?;
        if self.serving {
            let mut record = json.clone();
            record["header"] = schema::header_json(&m.header, true);
            self.writer.send(Command::LiveStatus {
                topic: caravan_schemas::topics::status().name().to_string(),
                stamp_ns: m.header.stamp_ns,
                bytes: serde_json::to_vec(&record)?,
            })?;
        }
        let Some(node) = json.get("node").and_then(Value::as_str).map(str::to_string) else {
            return Ok(());
        };
        if json["running"] == 1 {
            self.status_heard
                .insert(node.clone(), std::time::Instant::now());
            let field = |k: &str| json[k].as_u64().unwrap_or(0);
            self.status_series
                .entry(node.clone())
                .or_default()
                .push((field("rss_kib"), field("deadline_misses")));
        } else {
            self.status_heard.remove(&node);
        }
        self.node_status.insert(node, json.take());
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

    /// Drains what is left, waits for the writer to close the file and returns what the
    /// report needs.
    pub fn finish(mut self) -> Result<Recording> {
        self.drain()?;
        let mut topics = self.writer.finish()?;
        for (_, _, tap) in &self.taps {
            if let Some(s) = topics.get_mut(tap.topic()) {
                s.missed = tap.missed();
            }
        }
        Ok(Recording {
            topics,
            node_status: self.node_status,
            status_series: self.status_series,
        })
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_status_hash_is_the_status_topics() {
        assert_eq!(
            super::STATUS_HASH,
            caravan_schemas::topics::status().name_hash()
        );
    }
}
