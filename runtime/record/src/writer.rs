//! The recording's writer: the MCAP file, its Foxglove views and the live view, on a thread
//! of its own.
//!
//! The [`Recorder`](super::Recorder) runs on the launcher's driver thread, which in lockstep is
//! the scheduler's: it only copies each tapped message out of shared memory and hands the
//! batch over. Converting to JSON, deriving the views, compressing and writing happen here, on
//! the other core, while the next advance of simulated time runs. Commands are carried out in
//! the order they were sent and each batch is sorted as it always was, so a lockstep recording
//! is the same bytes whichever thread writes it.

use super::{scene, schema};
use anyhow::{Context, Result, anyhow};
use caravan::tap::Tapped;
use caravan_report::TopicCounter;
use caravan_schemas::descriptor::Descriptor;
use crossbeam::channel::{Receiver, Sender};
use foxglove::messages::FrameTransform;
use hdrhistogram::Histogram;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

/// Batches the writer may fall behind by before the recorder waits for it. A lockstep advance
/// is one batch; the bound keeps memory in check when writing is slower than the group.
const QUEUED_BATCHES: usize = 64;

/// How long the writer lets commands gather after it wrote some, before it looks again. The
/// recorder then never wakes it for a batch (a wake-up costs more than writing a lockstep
/// advance), only when the queue is half full; an idle writer sleeps until the next command.
const GATHER: Duration = Duration::from_millis(10);

/// Per-topic statistics seen by the recorder.
pub struct TopicStats {
    pub type_name: String,
    /// Messages written to the file, and the gaps in each source's `seq`.
    pub counted: TopicCounter,
    pub missed: u64,
    /// Wall-clock latency from send to the recorder's tap, ns.
    pub latency: Histogram<u64>,
}

impl TopicStats {
    fn new(type_name: &str) -> Self {
        Self {
            type_name: type_name.to_string(),
            counted: TopicCounter::default(),
            missed: 0,
            latency: Histogram::new_with_bounds(1, 3_600_000_000_000, 3).expect("valid bounds"),
        }
    }
}

/// What a recording says about its run: a `run` metadata record (seed, arguments, Caravan's
/// version; the wall-clock start only in realtime, where reruns differ anyway) and the resolved
/// launch file as the `launch.toml` attachment.
#[derive(Default)]
pub struct RecordingMeta {
    pub metadata: BTreeMap<String, String>,
    pub launch_file: Option<Vec<u8>>,
}

/// A topic the recorder opened a tap on.
pub struct NewTopic {
    /// The recorder's id for it, in the order of discovery; messages name it.
    pub id: usize,
    pub topic: String,
    pub type_name: &'static str,
    /// How its messages are laid out.
    pub descriptor: Arc<Descriptor>,
    /// Whether it goes into the file (else it is served live only).
    pub recorded: bool,
}

/// One message drained from a tap.
pub struct Drained {
    /// The tap's place among the taps sorted by topic, which orders messages of one stamp.
    pub rank: usize,
    /// The topic's [`NewTopic::id`].
    pub id: usize,
    pub message: Tapped,
}

/// What the recorder asks of the writer.
pub enum Command {
    /// Serve every topic to this live view too.
    Serve(super::live::LiveView),
    /// Newly discovered topics, sorted by name: their channels, before any of their messages.
    Topics(Vec<NewTopic>),
    /// The status topic: served live, never written.
    StatusTopic {
        topic: String,
        descriptor: Arc<Descriptor>,
    },
    /// Messages drained together, with the wall clock then (for the latency statistics).
    Batch {
        messages: Vec<Drained>,
        now_wall: u64,
    },
    /// A status message, for the live view.
    LiveStatus {
        topic: String,
        stamp_ns: u64,
        bytes: Vec<u8>,
    },
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
        .ok_or_else(|| anyhow!("an earlier write failed"))
        .with_context(cannot)?;
    op(w)
        .inspect_err(|_| {
            if let Some(w) = writer.take() {
                abandon(w);
            }
        })
        .with_context(cannot)
}

/// A topic the writer was told of, by [`NewTopic::id`].
struct Known {
    topic: String,
    type_name: &'static str,
    /// Its raw channel in the file; `None` for a topic served live only.
    channel: Option<u16>,
    /// Its Foxglove views, and their channels in the file (empty when not recorded).
    viewer: Option<scene::Viewer>,
    view_channels: Vec<u16>,
}

/// The MCAP file and the live view, fed by [`Command`]s.
struct Writer {
    /// `None` once a write failed (a full disk): see [`abandon`].
    writer: Option<McapWriter>,
    /// The MCAP file, for messages about it (a full disk).
    path: PathBuf,
    lockstep: bool,
    /// The topics by [`NewTopic::id`].
    topics: Vec<Option<Known>>,
    /// Statistics by [`NewTopic::id`], for topics with messages.
    stats: Vec<Option<TopicStats>>,
    channels: BTreeMap<String, u16>,
    /// Schema ids by name.
    schemas: BTreeMap<String, u16>,
    /// The last sequence number written, by channel id.
    sequences: Vec<u32>,
    live: Option<super::live::LiveView>,
    /// The JSON text of the message being written, kept between messages: sized for a map
    /// (a megabyte of cells), it is allocated once, not once per message.
    text: Vec<u8>,
    /// The text of its header, kept likewise.
    header: Vec<u8>,
    /// The views of the message being written, by [`scene::Viewer::topics`], kept between
    /// messages as `text` is.
    views: Vec<Vec<u8>>,
    /// The transforms the views of the time being written placed, for the file and for the
    /// live view: one `tf` message per time holds them ([`Self::write_frames`]).
    frames: Vec<FrameTransform>,
    live_frames: Vec<FrameTransform>,
    /// The time those transforms were placed at.
    frames_ns: u64,
    /// The transforms of the message being written, and the `tf` message's bytes, kept
    /// between messages as `text` is.
    placed: Vec<FrameTransform>,
    tf: Vec<u8>,
}

impl Writer {
    /// Creates the file with the run's metadata and attachment.
    fn create(path: &Path, lockstep: bool, meta: &RecordingMeta) -> Result<Self> {
        let file =
            File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
        // zstd's fastest level: a tenth of the launcher's CPU went to level 3's matching, for
        // files about a tenth larger (docs/benchmarks.md, "Efficiency").
        let mut options = mcap::WriteOptions::new()
            .library("caravan")
            .compression_level(1);
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
            writer,
            path: path.to_path_buf(),
            lockstep,
            topics: Vec::new(),
            channels: BTreeMap::new(),
            schemas: BTreeMap::new(),
            sequences: Vec::new(),
            stats: Vec::new(),
            live: None,
            text: Vec::new(),
            header: Vec::new(),
            views: Vec::new(),
            frames: Vec::new(),
            live_frames: Vec::new(),
            frames_ns: 0,
            placed: Vec::new(),
            tf: Vec::new(),
        })
    }

    fn handle(&mut self, command: Command) -> Result<()> {
        match command {
            Command::Serve(live) => self.live = Some(live),
            Command::Topics(topics) => {
                for topic in topics {
                    self.add_topic(topic)?;
                }
            }
            Command::StatusTopic { topic, descriptor } => {
                if let Some(live) = &mut self.live {
                    live.advertise_raw(&topic, &descriptor, true)?;
                }
            }
            Command::Batch {
                mut messages,
                now_wall,
            } => {
                messages.sort_by_key(|d| {
                    let h = &d.message.header;
                    (h.stamp_ns, d.rank, h.source_id, h.seq)
                });
                for drained in messages {
                    // The batch is in time order: a time's transforms are all in before the
                    // first message of the next.
                    let stamp_ns = drained.message.header.stamp_ns;
                    if stamp_ns != self.frames_ns {
                        self.write_frames()?;
                        self.frames_ns = stamp_ns;
                    }
                    self.write(drained, now_wall)?;
                }
                self.write_frames()?;
            }
            Command::LiveStatus {
                topic,
                stamp_ns,
                bytes,
            } => {
                if let Some(live) = &mut self.live {
                    live.log(&topic, stamp_ns, &bytes);
                }
            }
        }
        Ok(())
    }

    fn add_topic(&mut self, new: NewTopic) -> Result<()> {
        if self.topics.len() <= new.id {
            self.topics.resize_with(new.id + 1, || None);
            self.stats.resize_with(new.id + 1, || None);
        }
        let viewer = scene::Viewer::new(&new.topic, &new.descriptor);
        let views = viewer.as_ref().map_or(&[][..], |v| v.topics());
        let channel = match new.recorded {
            true => Some(self.channel(&new.topic, &new.descriptor)?),
            false => None,
        };
        let mut view_channels = Vec::new();
        for (view, schema) in views {
            if new.recorded {
                view_channels.push(self.scene_channel(view, *schema)?);
            }
            if let Some(live) = &mut self.live {
                live.advertise_view(view, schema())?;
            }
        }
        if viewer.as_ref().is_some_and(scene::Viewer::places_frames) {
            let (tf, schema) = scene::tf_view();
            if new.recorded {
                self.scene_channel(&tf, schema)?;
            }
            if let Some(live) = &mut self.live {
                live.advertise_view(&tf, schema())?;
            }
        }
        if let Some(live) = &mut self.live {
            live.advertise_raw(&new.topic, &new.descriptor, !self.lockstep)?;
        }
        self.topics[new.id] = Some(Known {
            topic: new.topic,
            type_name: new.type_name,
            channel,
            viewer,
            view_channels,
        });
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
    fn channel(&mut self, topic: &str, descriptor: &Descriptor) -> Result<u16> {
        if let Some(&id) = self.channels.get(topic) {
            return Ok(id);
        }
        let type_name = descriptor.type_name();
        let schema = schema::for_type(descriptor, !self.lockstep);
        let schema_id = self.schema_id(type_name, "jsonschema", schema.to_string().as_bytes())?;
        self.add_channel(topic, schema_id, "json")
    }

    /// A Foxglove view's channel, added with the first raw topic that has the view.
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

    fn write(&mut self, drained: Drained, now_wall: u64) -> Result<()> {
        let Writer {
            writer,
            path,
            lockstep,
            topics,
            stats,
            sequences,
            live,
            text,
            header,
            views,
            frames,
            live_frames,
            placed,
            ..
        } = self;
        let known = topics
            .get_mut(drained.id)
            .and_then(Option::as_mut)
            .ok_or_else(|| anyhow!("a message of a topic the recorder never announced"))?;
        let msg = drained.message;
        let stamp_ns = msg.header.stamp_ns;
        // Views and record are read straight from the message's bytes; the record's text is
        // what `serde_json::to_vec` of its JSON view gave (`Descriptor::write_json_text`).
        let viewed = match &mut known.viewer {
            Some(viewer) => {
                match viewer.encode(&msg.descriptor, &msg.bytes, stamp_ns, views, placed) {
                    true => viewer.topics(),
                    false => &[],
                }
            }
            None => &[],
        };
        let views = &views[..viewed.len()];
        header.clear();
        schema::write_header_json(&msg.header, !*lockstep, header);
        text.clear();
        msg.descriptor
            .write_json_text(&msg.bytes, Some(("header", header)), text)
            .map_err(|e| anyhow!("topic '{}': cannot convert to JSON: {e}", known.topic))?;
        if let Some(live) = live {
            live.log(&known.topic, stamp_ns, text);
            for ((topic, _), bytes) in viewed.iter().zip(views) {
                live.log(topic, stamp_ns, bytes);
            }
            live_frames.extend(placed.iter().cloned());
        }
        if known.channel.is_some() {
            frames.append(placed);
        }
        placed.clear();
        // Discovery gave every recorded topic its channel; the others are served live only.
        let Some(channel) = known.channel else {
            return Ok(());
        };
        write_message(writer, path, sequences, channel, stamp_ns, text)?;
        for (&channel, bytes) in known.view_channels.iter().zip(views) {
            write_message(writer, path, sequences, channel, stamp_ns, bytes)?;
        }
        let stats = stats[drained.id].get_or_insert_with(|| TopicStats::new(known.type_name));
        stats
            .counted
            .add(Some((msg.header.source_id, msg.header.seq)));
        stats
            .latency
            .saturating_record(now_wall.saturating_sub(msg.header.send_wall_ns).max(1));
        Ok(())
    }

    /// Writes the transforms placed at [`Self::frames_ns`] as one `tf` message, to the file
    /// and to the live view.
    fn write_frames(&mut self) -> Result<()> {
        let (tf, stamp_ns) = (scene::TF_TOPIC, self.frames_ns);
        if let Some(live) = self.live.as_mut().filter(|_| !self.live_frames.is_empty()) {
            scene::put_frames(&mut self.live_frames, &mut self.tf);
            live.log(tf, stamp_ns, &self.tf);
        }
        if self.frames.is_empty() {
            return Ok(());
        }
        let channel = *self
            .channels
            .get(tf)
            .ok_or_else(|| anyhow!("transforms of a topic without a `tf` channel"))?;
        scene::put_frames(&mut self.frames, &mut self.tf);
        let (writer, path, sequences) = (&mut self.writer, &self.path, &mut self.sequences);
        write_message(writer, path, sequences, channel, stamp_ns, &self.tf)
    }

    /// Writes the summary and flushes the file.
    fn finish(mut self) -> Result<BTreeMap<String, TopicStats>> {
        let stats = std::mem::take(&mut self.stats);
        with_writer(&mut self.writer, &self.path, |w| w.finish().map(|_| ()))?;
        if let Some(w) = self.writer.take() {
            // The last bytes leave the buffer here; a full disk must not pass unseen.
            use std::io::Write;
            w.into_inner()
                .flush()
                .with_context(|| cannot_write(&self.path))?;
        }
        Ok(self
            .topics
            .iter()
            .zip(stats)
            .filter_map(|(known, s)| Some((known.as_ref()?.topic.clone(), s?)))
            .collect())
    }
}

/// Writes one message on `channel`, numbered after the channel's last.
fn write_message(
    writer: &mut Option<McapWriter>,
    path: &Path,
    sequences: &mut Vec<u32>,
    channel: u16,
    stamp_ns: u64,
    data: &[u8],
) -> Result<()> {
    let index = usize::from(channel);
    if sequences.len() <= index {
        sequences.resize(index + 1, 0);
    }
    sequences[index] += 1;
    let header = mcap::records::MessageHeader {
        channel_id: channel,
        sequence: sequences[index],
        log_time: stamp_ns,
        publish_time: stamp_ns,
    };
    with_writer(writer, path, |w| w.write_to_known_channel(&header, data))
}

/// The writer's thread, seen from the recorder.
pub struct WriterThread {
    commands: Option<Sender<Command>>,
    thread: Option<std::thread::JoinHandle<Result<BTreeMap<String, TopicStats>>>>,
}

impl WriterThread {
    /// Creates the file (its metadata and attachment written) and starts the thread.
    pub fn start(path: &Path, lockstep: bool, meta: &RecordingMeta) -> Result<Self> {
        let mut writer = Writer::create(path, lockstep, meta)?;
        let (commands, queue): (Sender<Command>, Receiver<Command>) =
            crossbeam::channel::bounded(QUEUED_BATCHES);
        let thread = std::thread::Builder::new()
            .name("recording writer".into())
            .spawn(move || {
                while let Ok(command) = queue.recv() {
                    writer.handle(command)?;
                    for command in queue.try_iter() {
                        writer.handle(command)?;
                    }
                    std::thread::park_timeout(GATHER);
                }
                writer.finish()
            })
            .context("cannot start the recording's writer thread")?;
        Ok(Self {
            commands: Some(commands),
            thread: Some(thread),
        })
    }

    /// Queues `command`; waits while the writer is [`QUEUED_BATCHES`] behind. A writer that
    /// failed (a full disk) makes this fail with its error.
    pub fn send(&mut self, command: Command) -> Result<()> {
        let sent = match &self.commands {
            Some(commands) => commands.send(command).is_ok(),
            None => false,
        };
        if sent {
            // Wake a gathering writer before the queue is full (see GATHER).
            if let (Some(commands), Some(thread)) = (&self.commands, &self.thread)
                && commands.len() >= QUEUED_BATCHES / 2
            {
                thread.thread().unpark();
            }
            return Ok(());
        }
        Err(self
            .join()
            .err()
            .unwrap_or_else(|| anyhow!("the recording's writer has stopped")))
    }

    /// Waits for every queued command to be written, closes the file and returns the
    /// statistics.
    pub fn finish(mut self) -> Result<BTreeMap<String, TopicStats>> {
        self.join()
    }

    fn join(&mut self) -> Result<BTreeMap<String, TopicStats>> {
        self.commands = None;
        let thread = self
            .thread
            .take()
            .ok_or_else(|| anyhow!("the recording's writer has stopped"))?;
        thread
            .join()
            .map_err(|_| anyhow!("the recording's writer thread panicked"))?
    }
}
