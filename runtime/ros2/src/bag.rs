//! rosbag2 bags, as ROS 2's `ros2 bag` writes them with its MCAP storage: a directory `OUT`
//! holding `metadata.yaml` and one MCAP file `OUT_0.mcap` (profile `ros2`; one `ros2msg`
//! schema per type, named `pkg/msg/Type`; channels of `cdr` messages with their
//! `offered_qos_profiles`). [`BagWriter`] writes one, [`read_bag`] reads one back (a directory,
//! or its `.mcap` file alone) for the types Caravan maps.

use crate::mapping::RosMessage;
use crate::msgs::to_cdr;
use crate::ros_type::RosType;
use anyhow::{Context, Result, anyhow, bail};
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// The rosbag2 metadata version written: 5, which every ROS 2 release since Humble reads.
pub const METADATA_VERSION: u32 = 5;

/// The offered QoS of a topic as rosbag2's metadata (version 5) writes it, a YAML text: keep
/// last `depth`, reliable, volatile, or transient local when `latched` (a map, as
/// `map_server` offers it); deadline, lifespan and lease left at the middleware's default.
pub fn offered_qos(latched: bool, depth: u32) -> String {
    let default_time = "\n    sec: 0\n    nsec: 0";
    format!(
        "- history: 1\n  depth: {depth}\n  reliability: 1\n  durability: {}\n  \
         deadline:{default_time}\n  lifespan:{default_time}\n  liveliness: 1\n  \
         liveliness_lease_duration:{default_time}\n  avoid_ros_namespace_conventions: false",
        if latched { 1 } else { 2 }
    )
}

struct Topic {
    name: String,
    ty: RosType,
    qos: String,
    channel: u16,
    count: u64,
}

/// What [`BagWriter::finish`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct Written {
    /// Each topic, its type and its messages, in the order they were added.
    pub topics: Vec<(String, RosType, u64)>,
    pub messages: u64,
    /// The MCAP file.
    pub file: PathBuf,
}

/// Writes a rosbag2 bag: [`BagWriter::create`], a topic at a time ([`BagWriter::add_topic`]),
/// messages ([`BagWriter::write`]), then [`BagWriter::finish`], which writes `metadata.yaml`.
pub struct BagWriter {
    dir: PathBuf,
    file_name: String,
    mcap: mcap::Writer<BufWriter<File>>,
    topics: Vec<Topic>,
    by_name: BTreeMap<String, usize>,
    schemas: BTreeMap<RosType, u16>,
    span: Option<(u64, u64)>,
}

impl BagWriter {
    /// Creates the directory `dir` (which must not exist; its parent must) and its MCAP file.
    pub fn create(dir: &Path) -> Result<BagWriter> {
        let name = dir
            .file_name()
            .and_then(|n| n.to_str())
            .filter(|n| !n.is_empty() && *n != "." && *n != "..")
            .ok_or_else(|| anyhow!("{}: not a name for a bag directory", dir.display()))?;
        let file_name = format!("{name}_0.mcap");
        std::fs::create_dir(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        let path = dir.join(&file_name);
        let mcap = File::create(&path)
            .with_context(|| format!("cannot create {}", path.display()))
            .and_then(|file| {
                mcap::WriteOptions::new()
                    .profile("ros2")
                    .library(concat!("caravan-ros2 ", env!("CARGO_PKG_VERSION")))
                    .create(BufWriter::new(file))
                    .with_context(|| format!("cannot write {}", path.display()))
            });
        let mcap = match mcap {
            Ok(m) => m,
            Err(e) => {
                let _ = std::fs::remove_dir_all(dir);
                return Err(e);
            }
        };
        Ok(BagWriter {
            dir: dir.to_path_buf(),
            file_name,
            mcap,
            topics: Vec::new(),
            by_name: BTreeMap::new(),
            schemas: BTreeMap::new(),
            span: None,
        })
    }

    /// The MCAP file's path.
    pub fn file(&self) -> PathBuf {
        self.dir.join(&self.file_name)
    }

    /// Adds topic `name` of type `ty` offered with `qos` ([`offered_qos`]); a topic added again
    /// with the same type is the same topic, with another type an error.
    pub fn add_topic(&mut self, name: &str, ty: RosType, qos: &str) -> Result<()> {
        if let Some(&k) = self.by_name.get(name) {
            let had = self.topics[k].ty;
            if had != ty {
                bail!(
                    "topic {name} is a {} already, not a {}",
                    had.name(),
                    ty.name()
                );
            }
            return Ok(());
        }
        let schema = match self.schemas.get(&ty) {
            Some(&id) => id,
            None => {
                let id = self
                    .mcap
                    .add_schema(&ty.name(), "ros2msg", ty.definition().as_bytes())?;
                self.schemas.insert(ty, id);
                id
            }
        };
        let metadata = BTreeMap::from([("offered_qos_profiles".to_string(), qos.to_string())]);
        let channel = self.mcap.add_channel(schema, name, "cdr", &metadata)?;
        self.by_name.insert(name.to_string(), self.topics.len());
        self.topics.push(Topic {
            name: name.to_string(),
            ty,
            qos: qos.to_string(),
            channel,
            count: 0,
        });
        Ok(())
    }

    /// Writes a CDR message on `topic` (added before) at `time_ns`, its log and publish time.
    pub fn write(&mut self, topic: &str, time_ns: u64, cdr: &[u8]) -> Result<()> {
        let &k = self
            .by_name
            .get(topic)
            .ok_or_else(|| anyhow!("topic {topic} was not added to the bag"))?;
        let t = &mut self.topics[k];
        t.count += 1;
        let header = mcap::records::MessageHeader {
            channel_id: t.channel,
            sequence: t.count as u32,
            log_time: time_ns,
            publish_time: time_ns,
        };
        self.mcap
            .write_to_known_channel(&header, cdr)
            .with_context(|| {
                format!("cannot write {}", self.dir.join(&self.file_name).display())
            })?;
        self.span = Some(match self.span {
            None => (time_ns, time_ns),
            Some((a, b)) => (a.min(time_ns), b.max(time_ns)),
        });
        Ok(())
    }

    /// Writes `message` on `topic` at `time_ns`, encoded in CDR.
    pub fn write_message(&mut self, topic: &str, time_ns: u64, message: &RosMessage) -> Result<()> {
        self.write(topic, time_ns, &to_cdr(message))
    }

    /// Ends the MCAP file (its summary, and the bag's metadata as a `rosbag2` metadata record,
    /// as rosbag2 writes it) and writes `metadata.yaml`.
    pub fn finish(mut self) -> Result<Written> {
        let path = self.file();
        let yaml = self.metadata_yaml();
        let record = mcap::records::Metadata {
            name: "rosbag2".into(),
            metadata: BTreeMap::from([("serialized_metadata".to_string(), yaml.clone())]),
        };
        self.mcap
            .write_metadata(&record)
            .and_then(|_| self.mcap.finish().map(|_| ()))
            .with_context(|| format!("cannot write {}", path.display()))?;
        let mut file = self.mcap.into_inner();
        std::io::Write::flush(&mut file)
            .with_context(|| format!("cannot write {}", path.display()))?;
        let indented: String = yaml.lines().map(|l| format!("  {l}\n")).collect();
        let meta = self.dir.join("metadata.yaml");
        std::fs::write(&meta, format!("rosbag2_bagfile_information:\n{indented}"))
            .with_context(|| format!("cannot write {}", meta.display()))?;
        Ok(Written {
            topics: self
                .topics
                .iter()
                .map(|t| (t.name.clone(), t.ty, t.count))
                .collect(),
            messages: self.topics.iter().map(|t| t.count).sum(),
            file: path,
        })
    }

    /// The bag's metadata (the fields of `rosbag2_bagfile_information`), YAML.
    fn metadata_yaml(&self) -> String {
        let q = |s: &str| serde_json::to_string(s).expect("a string serialises");
        let (start, end) = self.span.unwrap_or((0, 0));
        let duration = end - start;
        let count: u64 = self.topics.iter().map(|t| t.count).sum();
        let mut y = format!(
            "version: {METADATA_VERSION}\nstorage_identifier: mcap\nduration:\n  nanoseconds: \
             {duration}\nstarting_time:\n  nanoseconds_since_epoch: {start}\nmessage_count: \
             {count}\ntopics_with_message_count:\n"
        );
        if self.topics.is_empty() {
            y = y.replace(
                "topics_with_message_count:\n",
                "topics_with_message_count: []\n",
            );
        }
        for t in &self.topics {
            y.push_str(&format!(
                "  - topic_metadata:\n      name: {}\n      type: {}\n      \
                 serialization_format: cdr\n      offered_qos_profiles: {}\n    \
                 message_count: {}\n",
                q(&t.name),
                q(&t.ty.name()),
                q(&t.qos),
                t.count
            ));
        }
        let file = q(&self.file_name);
        y.push_str(&format!(
            "compression_format: \"\"\ncompression_mode: \"\"\nrelative_file_paths:\n  - {file}\n\
             files:\n  - path: {file}\n    starting_time:\n      nanoseconds_since_epoch: \
             {start}\n    duration:\n      nanoseconds: {duration}\n    message_count: {count}\n"
        ));
        y
    }
}

/// One message of a bag.
#[derive(Debug, Clone, PartialEq)]
pub struct BagMessage {
    pub topic: String,
    pub ty: RosType,
    /// The time the bag logged it (received or, in a bag Caravan wrote, its stamp), ns.
    pub log_ns: u64,
    /// The message, CDR-encoded as a ROS 2 middleware sends it.
    pub cdr: Vec<u8>,
}

/// A bag read back.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Bag {
    /// Every topic with its type, those without messages too, sorted by name.
    pub topics: BTreeMap<String, RosType>,
    /// The messages in log-time order (the order of the files for equal times).
    pub messages: Vec<BagMessage>,
}

/// The profile an MCAP file's header names (`ros2` for a rosbag2 file), if `bytes` start as an
/// MCAP file does.
pub fn mcap_profile(bytes: &[u8]) -> Option<&str> {
    // Magic (8 bytes), the header's opcode 0x01 and its length (u64), then the profile as a
    // u32 length and its bytes.
    let rest = bytes.strip_prefix(mcap::MAGIC)?.strip_prefix(&[0x01])?;
    let len = u32::from_le_bytes(rest.get(8..12)?.try_into().ok()?) as usize;
    std::str::from_utf8(rest.get(12..12usize.checked_add(len)?)?).ok()
}

/// Whether `path` is meant as a rosbag2 bag: a directory (its `metadata.yaml` is looked for
/// when it is read) or an MCAP file of profile `ros2`.
pub fn is_bag(path: &Path) -> bool {
    if path.is_dir() {
        return true;
    }
    let Ok(bytes) = caravan::input::map_recording(path) else {
        return false;
    };
    mcap_profile(&bytes) == Some("ros2")
}

/// Reads a bag: a rosbag2 directory (MCAP storage) or one of its `.mcap` files. Every type in
/// it must be one Caravan maps ([`RosType`]); anything else, and a file that is missing,
/// truncated or not what it should be, is an error naming the file.
pub fn read_bag(path: &Path) -> Result<Bag> {
    let mut bag = Bag::default();
    if path.is_dir() {
        for file in bag_files(path)? {
            read_mcap(&file, &mut bag)?;
        }
    } else {
        read_mcap(path, &mut bag)?;
    }
    bag.messages.sort_by_key(|m| m.log_ns);
    Ok(bag)
}

fn unknown_type(file: &Path, topic: &str, name: &str) -> anyhow::Error {
    let known: Vec<String> = RosType::ALL.iter().map(|t| t.name()).collect();
    anyhow!(
        "{}: topic {topic} has type {name}, which Caravan does not map (it maps {})",
        file.display(),
        known.join(", ")
    )
}

/// The MCAP files `dir/metadata.yaml` lists, after checking its topics' types.
fn bag_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let meta = dir.join("metadata.yaml");
    if !meta.is_file() {
        bail!(
            "{}: a directory without metadata.yaml, so not a rosbag2 bag",
            dir.display()
        );
    }
    let text = caravan::input::read_to_string(&meta)
        .with_context(|| format!("cannot read {}", meta.display()))?;
    let yaml: serde_yaml::Value =
        serde_yaml::from_str(&text).with_context(|| format!("{}: not YAML", meta.display()))?;
    let info = &yaml["rosbag2_bagfile_information"];
    let bad = |what: &str| anyhow!("{}: {what}", meta.display());
    if info.is_null() {
        return Err(bad("no rosbag2_bagfile_information"));
    }
    match info["storage_identifier"].as_str() {
        Some("mcap") => {}
        Some(other) => {
            return Err(bad(&format!(
                "storage '{other}': Caravan reads bags of MCAP storage (`ros2 bag convert` \
                 converts others)"
            )));
        }
        None => return Err(bad("no storage_identifier")),
    }
    let mode = info["compression_mode"].as_str().unwrap_or("");
    if !mode.is_empty() && !mode.eq_ignore_ascii_case("none") {
        return Err(bad(&format!(
            "compression mode '{mode}': Caravan reads uncompressed bags (MCAP's own chunk \
             compression is fine)"
        )));
    }
    let topics = info["topics_with_message_count"].as_sequence();
    for t in topics.map(Vec::as_slice).unwrap_or(&[]) {
        let m = &t["topic_metadata"];
        let (Some(name), Some(ty)) = (m["name"].as_str(), m["type"].as_str()) else {
            return Err(bad("a topic without a name or a type"));
        };
        if RosType::parse(ty).is_none() {
            return Err(unknown_type(&meta, name, ty));
        }
        if let Some(format) = m["serialization_format"].as_str().filter(|f| *f != "cdr") {
            return Err(bad(&format!(
                "topic {name}: serialization format '{format}', not cdr"
            )));
        }
    }
    let files = info["relative_file_paths"]
        .as_sequence()
        .ok_or_else(|| bad("no relative_file_paths"))?;
    files
        .iter()
        .map(|f| {
            // As rosbag2 and rosbags do: the file's name, in the bag's directory.
            let name = f
                .as_str()
                .and_then(|f| Path::new(f).file_name())
                .ok_or_else(|| bad("a relative_file_paths entry is not a file name"))?;
            Ok(dir.join(name))
        })
        .collect()
}

/// Reads the topics and messages of one rosbag2 MCAP file into `bag`.
fn read_mcap(path: &Path, bag: &mut Bag) -> Result<()> {
    let at = || path.display().to_string();
    let bytes =
        caravan::input::map_recording(path).with_context(|| format!("cannot read {}", at()))?;
    match mcap_profile(&bytes) {
        Some("ros2") => {}
        Some(other) => bail!(
            "{}: an MCAP file of profile '{other}', not a rosbag2 file (ros2)",
            at()
        ),
        None => bail!("{} is not an MCAP file", at()),
    }
    let damaged = |e: mcap::McapError| anyhow!("{}: a truncated or damaged MCAP file: {e}", at());
    let mut types: BTreeMap<u16, RosType> = BTreeMap::new();
    let mut check = |bag: &mut Bag, c: &mcap::Channel| -> Result<RosType> {
        if let Some(&ty) = types.get(&c.id) {
            return Ok(ty);
        }
        let name = c.schema.as_ref().map(|s| s.name.as_str()).unwrap_or("");
        if name.is_empty() {
            bail!("{}: topic {} has no schema, so no type", at(), c.topic);
        }
        let ty = RosType::parse(name).ok_or_else(|| unknown_type(path, &c.topic, name))?;
        if c.message_encoding != "cdr" {
            bail!(
                "{}: topic {}: message encoding '{}', not cdr",
                at(),
                c.topic,
                c.message_encoding
            );
        }
        if let Some(had) = bag.topics.insert(c.topic.clone(), ty).filter(|t| *t != ty) {
            bail!(
                "{}: topic {} is both a {} and a {}",
                at(),
                c.topic,
                had.name(),
                ty.name()
            );
        }
        types.insert(c.id, ty);
        Ok(ty)
    };
    // Channels without messages appear only in the summary (a file cut short has none).
    if let Ok(Some(summary)) = mcap::Summary::read(&bytes) {
        for c in summary.channels.values() {
            check(bag, c)?;
        }
    }
    for message in mcap::MessageStream::new(&bytes).map_err(damaged)? {
        let message = message.map_err(damaged)?;
        let ty = check(bag, &message.channel)?;
        bag.messages.push(BagMessage {
            topic: message.channel.topic.clone(),
            ty,
            log_ns: message.log_time,
            cdr: message.data.into_owned(),
        });
    }
    Ok(())
}

#[cfg(test)]
#[path = "bag_tests.rs"]
mod tests;
