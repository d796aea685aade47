//! `caravan play FILE.mcap`: a recording's topics played back into a group, as `ros2 bag play`.
//!
//! - **Into a running group** (`caravan play FILE`): from outside it, at the recorded pace
//!   times `--speed`. The group's clock is not touched, so this suits realtime groups.
//! - **As a node of the group** (`caravan launch FILE --play REC`): the launcher adds the
//!   player `caravan-play`, which steps at each recorded message's stamp in the group's clock.
//!   In lockstep every message reaches its subscribers at the simulated time it did when it
//!   was recorded, with its recorded header, so a node fed the recording sees what it saw
//!   then. `caravan resim` is built on this.

use crate::bad_input::{as_bad, bad};
use crate::clean::choose_group;
use crate::inject::{sleep_until, source_id};
pub use crate::recording::{Recorded, Recording};
use crate::watch::{GroupArg, GroupEnd, iox};
use anyhow::{Context, Result, bail};
use caravan::inject::{DynInject, open_injector};
use caravan::{Delivery, Header, Trigger};
use caravan_launch::model::{Exec, LaunchFile, ProcessSpec, Restart};
use caravan_schemas::lockstep::name_hash;
use clap::Args;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The player's node name in a launched group.
pub const PLAYER: &str = "caravan-play";

/// A new topic's contract when the player is the first to open it (one nobody subscribes to).
const NEW_TOPIC: Delivery = Delivery::Latest { depth: 8 };

#[derive(Args)]
pub struct PlayArgs {
    /// The recording (a run's record.mcap, or one made by `caravan record`), or a rosbag2 bag
    /// of the types Caravan maps (a directory with metadata.yaml, or its .mcap)
    pub file: PathBuf,
    #[command(flatten)]
    pub group: GroupArg,
    /// Only these topics (as in the launch file's `record`: names or patterns with *)
    #[arg(long, num_args = 1..)]
    pub topics: Vec<String>,
    /// Playback speed: 2 plays twice as fast as recorded
    #[arg(long, default_value = "1", value_parser = speed_arg)]
    pub speed: f64,
    /// Play as the group's node `caravan-play` (the launcher's `--play` starts it so)
    #[arg(long, hide = true)]
    pub in_group: bool,
    /// With --in-group: leave out what this node published, and first check that the
    /// recording holds every topic it subscribes to (`caravan resim`)
    #[arg(long, hide = true, requires = "in_group")]
    pub under_test: Option<String>,
}

fn speed_arg(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(s) if s > 0.0 && s <= 1000.0 => Ok(s),
        _ => Err(format!(
            "'{text}': expected a speed above 0 and at most 1000"
        )),
    }
}

/// Reads the Caravan channels of `path` that `patterns` select (all when empty). A rosbag2
/// bag (a directory, or an MCAP file of profile `ros2`) is read as the recording of its
/// mapped topics (see `bag.rs`).
pub fn read_recording(path: &Path, patterns: &[String]) -> Result<Recording> {
    caravan_report::guarded(path.display(), || read_unguarded(path, patterns))
}

fn read_unguarded(path: &Path, patterns: &[String]) -> Result<Recording> {
    if caravan_ros2::bag::is_bag(path) {
        return crate::bag::read_bag_recording(path, patterns);
    }
    let bytes = caravan::input::map_recording(path)
        .with_context(|| format!("cannot read {}", path.display()))?;
    if !bytes.starts_with(mcap::MAGIC) {
        bail!("{} is not an MCAP file", path.display());
    }
    let at = || path.display().to_string();
    let caravan_channel = |c: &mcap::Channel| {
        c.message_encoding == "json"
            && c.topic != "status"
            && c.schema
                .as_ref()
                .is_some_and(|s| s.encoding == "jsonschema" && s.name.contains("::"))
    };
    let chosen = |topic: &str| crate::recording::selected(patterns, topic);
    let mut recording = Recording::default();
    let describe = |recording: &mut Recording, c: &mcap::Channel| -> Result<()> {
        let schema = c.schema.as_ref().expect("checked");
        if recording.descriptors.contains_key(&schema.name) {
            return Ok(());
        }
        let Some(d) = caravan_record::schema::recorded_descriptor(&schema.data) else {
            return Ok(());
        };
        let d = d
            .ok()
            .filter(|d| d.type_name() == schema.name)
            .with_context(|| {
                format!(
                    "{}: the schema of channel '{}' does not describe '{}'",
                    at(),
                    c.topic,
                    schema.name
                )
            })?;
        recording.descriptors.insert(schema.name.clone(), d);
        Ok(())
    };
    // Channels without messages appear only in the summary.
    if let Some(summary) = mcap::Summary::read(&bytes).ok().flatten() {
        for c in summary.channels.values().filter(|c| caravan_channel(c)) {
            recording.topics.push(c.topic.clone());
            if chosen(&c.topic) {
                let schema = c.schema.as_ref().expect("checked").name.clone();
                recording.types.insert(c.topic.clone(), schema);
                describe(&mut recording, c)?;
            }
        }
    }
    for message in crate::recording::messages(&bytes).with_context(at)? {
        // A damaged chunk is named (its number, bytes and log times).
        let message = message
            .map_err(|e| match crate::recording::damaged_chunk(&bytes) {
                Some(chunk) => anyhow::anyhow!("{chunk}"),
                None => e.into(),
            })
            .with_context(at)?;
        let channel = &message.channel;
        if !caravan_channel(channel) {
            continue;
        }
        if !recording.topics.contains(&channel.topic) {
            recording.topics.push(channel.topic.clone());
        }
        if !chosen(&channel.topic) {
            continue;
        }
        let schema = channel.schema.as_ref().expect("checked").name.clone();
        if recording
            .types
            .insert(channel.topic.clone(), schema)
            .is_none()
        {
            describe(&mut recording, channel)?;
        }
        // mcap checks a chunk's CRC after its last message: a message it gave first may be
        // one the damage garbled, so the damaged chunk is named rather than the message.
        let json: Value = serde_json::from_slice(&message.data)
            .map_err(|e| match crate::recording::damaged_chunk(&bytes) {
                Some(chunk) => anyhow::anyhow!("{chunk}"),
                None => anyhow::anyhow!("a message on {} is not JSON: {e}", channel.topic),
            })
            .with_context(at)?;
        let h = &json["header"];
        let field = |k: &str| caravan_report::as_u64(&h[k]);
        recording.messages.push(Recorded {
            log_ns: message.log_time,
            topic: channel.topic.clone(),
            seq: field("seq").unwrap_or(0),
            stamp_ns: field("stamp_ns").unwrap_or(message.log_time),
            source_id: field("source_id").unwrap_or_else(|| source_id("play")),
            data: message.data.into_owned(),
            json,
        });
    }
    recording.topics.sort();
    recording.messages.sort_by_key(|m| m.log_ns);
    Ok(recording)
}

/// The recorded header of `m`, sent now.
fn header(m: &Recorded) -> Header {
    Header {
        seq: m.seq,
        stamp_ns: m.stamp_ns,
        send_wall_ns: caravan::wall_clock_ns(),
        source_id: m.source_id,
    }
}

/// Plays into a running group from outside it.
pub fn play(args: &PlayArgs) -> Result<()> {
    if args.in_group {
        return play_in_group(args);
    }
    let recording = read_recording(&args.file, &args.topics).map_err(as_bad)?;
    if recording.messages.is_empty() {
        return Err(bad(nothing_to_play(&args.file, &args.topics)));
    }
    let group = choose_group(args.group.group.as_deref())?;
    let (config, node) = iox(&group)?;
    recording.adopt_types(&config)?;
    let Recording {
        types, messages, ..
    } = recording;
    let mut injectors: BTreeMap<&str, Box<dyn DynInject>> = BTreeMap::new();
    for (topic, type_name) in &types {
        injectors.insert(topic, open_injector(&node, topic, type_name, NEW_TOPIC)?);
    }
    let first = messages[0].log_ns;
    let start = Instant::now();
    let mut group_end = GroupEnd::watch(&group);
    let mut played = 0u64;
    for m in &messages {
        let due = start + Duration::from_secs_f64((m.log_ns - first) as f64 / 1e9 / args.speed);
        if !sleep_until(&node, due) || group_end.ended()? {
            break;
        }
        // The recorded header travels with the message, so subscribers see the original
        // sequence numbers, stamps and sources.
        injectors[m.topic.as_str()].publish_json(header(m), &m.json)?;
        played += 1;
    }
    eprintln!(
        "caravan: played {played} of {} messages on {} topics into group '{group}'",
        messages.len(),
        types.len()
    );
    Ok(())
}

fn nothing_to_play(file: &Path, topics: &[String]) -> String {
    format!(
        "{}: no recorded Caravan messages to play{}",
        file.display(),
        if topics.is_empty() {
            String::new()
        } else {
            format!(" on {}", topics.join(", "))
        }
    )
}

/// What `caravan launch --play` asks for: the player as one of the group's processes.
pub struct InGroup {
    pub file: PathBuf,
    pub topics: Vec<String>,
    /// The node `caravan resim` runs again: its own messages are not played.
    pub under_test: Option<String>,
}

impl InGroup {
    /// The player's process, once the recording is known to hold something to play.
    pub fn process(&self, lf: &LaunchFile) -> Result<ProcessSpec> {
        if lf.processes.iter().any(|p| p.name == PLAYER) {
            bail!(
                "--play: {} already has a process named '{PLAYER}', the player's name",
                lf.path.display()
            );
        }
        let file = std::path::absolute(&self.file)
            .with_context(|| format!("--play {}", self.file.display()))?;
        let recording = read_recording(&file, &self.topics)
            .with_context(|| format!("--play {}", self.file.display()))?;
        let skipped = self.under_test.as_deref().map(name_hash);
        if !recording
            .messages
            .iter()
            .any(|m| Some(m.source_id) != skipped)
        {
            bail!("--play: {}", nothing_to_play(&self.file, &self.topics));
        }
        let exe = std::env::current_exe().context("cannot find the caravan program")?;
        let mut words = vec![
            exe.display().to_string(),
            "play".into(),
            file.display().to_string(),
            "--in-group".into(),
        ];
        if !self.topics.is_empty() {
            words.push("--topics".into());
            words.extend(self.topics.iter().cloned());
        }
        if let Some(node) = &self.under_test {
            words.extend(["--under-test".into(), node.clone()]);
        }
        Ok(ProcessSpec {
            name: PLAYER.into(),
            exec: Exec::Command(words),
            args: Vec::new(),
            host: ProcessSpec::DEFAULT_HOST.into(),
            rate: None,
            on: None,
            spin: None,
            params: serde_json::json!({}),
            restart: Restart::Never,
            restart_backoff: ProcessSpec::DEFAULT_BACKOFF,
            max_restarts: 0,
            required: true,
            ends_group: false,
            env: BTreeMap::new(),
            check: Some(false),
            container: None,
            launch_dir: std::env::current_dir().context("cannot read the current directory")?,
        })
    }
}

/// The player as a node of the group: a step at each recorded stamp publishes the messages
/// stamped then, with their recorded headers.
fn play_in_group(args: &PlayArgs) -> Result<()> {
    let recording = read_recording(&args.file, &args.topics).map_err(as_bad)?;
    let mut node = caravan::Node::from_env()?;
    recording.adopt_types(&caravan::group::config(node.group())?)?;
    let Recording {
        types,
        mut messages,
        topics: recorded,
        ..
    } = recording;
    if let Some(name) = &args.under_test {
        let skipped = name_hash(name);
        messages.retain(|m| m.source_id != skipped);
    }
    // In lockstep recordings log time is the stamp already; in realtime ones the stamp is
    // the group's time, which the player's clock counts too.
    messages.sort_by_key(|m| m.stamp_ns);
    let group = node.group().to_string();
    let injectors = node.injectors();
    let mut open: BTreeMap<String, Box<dyn DynInject>> = BTreeMap::new();
    let mut next = 0;
    node.run(Trigger::Scheduled, |step| {
        if step.index() == 0
            && let Some(name) = &args.under_test
        {
            // Every node has made its ports before the first lockstep step.
            check_inputs(&group, name, &recorded)
                .map_err(|e| caravan::Error::Config(e.to_string()))?;
        }
        while let Some(m) = messages.get(next).filter(|m| m.stamp_ns <= step.now_ns()) {
            // Opened when first due, so a topic the group's nodes made keeps their contract.
            if !open.contains_key(&m.topic) {
                let injector = injectors.open(&m.topic, &types[&m.topic], NEW_TOPIC)?;
                open.insert(m.topic.clone(), injector);
            }
            open[&m.topic].publish_json(header(m), &m.json)?;
            next += 1;
        }
        if let Some(m) = messages.get(next) {
            step.wake_at(Duration::from_nanos(m.stamp_ns));
        }
        Ok(())
    })?;
    Ok(())
}

/// Fails when `node` subscribes to a topic the recording does not hold: its outputs would
/// then differ for want of an input, not because of the node.
fn check_inputs(group: &str, node: &str, recorded: &[String]) -> Result<()> {
    let (_, subscribes) = crate::graph::topics_of(group, node)?;
    let missing: Vec<&String> = subscribes
        .iter()
        .filter(|t| !recorded.contains(t))
        .collect();
    if !missing.is_empty() {
        bail!(
            "node '{node}' subscribes to {}, which the recording does not hold; add {} to the \
             group's `record` and record again",
            join(&missing),
            if missing.len() == 1 { "it" } else { "them" }
        );
    }
    Ok(())
}

fn join(topics: &[&String]) -> String {
    topics
        .iter()
        .map(|t| t.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}
