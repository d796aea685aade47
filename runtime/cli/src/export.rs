//! `caravan export --ros2 REC.mcap OUT`: a recording as a rosbag2 bag that ROS 2's tools read
//! (`ros2 bag info`, `ros2 bag play`, rosbags, Foxglove). Each recorded topic whose type has a
//! ROS 2 counterpart is written under its ROS name with its header stamp as log time, and
//! `/tf` holds the frames of the recording's own `tf` channel (`caravan_ros2::recorded`).
//! Bad input (OUT exists, a recording that cannot be read or converted, nothing to export)
//! exits 2 and leaves nothing behind; a failure to write exits 1.

use anyhow::{Result, anyhow};
use caravan_group::launch::EXIT_BAD_INPUT;
use caravan_group::play::read_recording;
use caravan_ros2::bag::{BagWriter, Written, offered_qos};
use caravan_ros2::naming::{check_topic, ros_topic};
use caravan_ros2::recorded::{TF_TOPIC, export as convert, exported_type, places_frames};
use caravan_ros2::ros_type::RosType;
use clap::Args;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct ExportArgs {
    /// Write a rosbag2 bag (MCAP storage, CDR messages), as `ros2 bag record` does
    #[arg(long, required = true)]
    pub ros2: bool,
    /// The recording (a run directory's record.mcap)
    pub file: PathBuf,
    /// The bag directory to make; it must not exist
    pub out: PathBuf,
}

/// What goes where: each exported Caravan topic's ROS topic and type, and the topics that
/// place frames on `/tf`.
struct Plan {
    own: BTreeMap<String, (String, RosType)>,
    tf: Vec<String>,
    left_out: Vec<String>,
}

/// Bad input: the message and exit 2.
struct Bad(anyhow::Error);

pub fn export(args: &ExportArgs) -> Result<u8> {
    match run(args) {
        Ok(Ok(())) => Ok(0),
        Ok(Err(Bad(e))) => {
            eprintln!("caravan: {e:#}");
            Ok(EXIT_BAD_INPUT)
        }
        Err(e) => Err(e),
    }
}

fn plan(types: &BTreeMap<String, String>, file: &Path) -> Result<Plan, Bad> {
    let mut plan = Plan {
        own: BTreeMap::new(),
        tf: Vec::new(),
        left_out: Vec::new(),
    };
    let mut taken: BTreeMap<String, &str> = BTreeMap::new();
    for (topic, caravan_type) in types {
        let own = exported_type(caravan_type);
        let tf = places_frames(topic, caravan_type);
        if tf {
            plan.tf.push(topic.clone());
        }
        let Some(ty) = own else {
            if !tf {
                plan.left_out.push(format!("{topic} ({caravan_type})"));
            }
            continue;
        };
        let ros = ros_topic(topic);
        if let Err(why) = check_topic(&ros) {
            plan.left_out.push(format!("{topic} ({why})"));
            continue;
        }
        if let Some(other) = taken.insert(ros.clone(), topic) {
            return Err(Bad(anyhow!(
                "{}: topics {other} and {topic} would both be ROS 2 topic {ros}",
                file.display()
            )));
        }
        plan.own.insert(topic.clone(), (ros, ty));
    }
    if let Some(topic) = taken.get(TF_TOPIC).filter(|_| !plan.tf.is_empty()) {
        return Err(Bad(anyhow!(
            "{}: topic {topic} would be ROS 2 topic {TF_TOPIC}, which holds the robots' frames",
            file.display()
        )));
    }
    if plan.own.is_empty() && plan.tf.is_empty() {
        return Err(Bad(anyhow!(
            "{}: no recorded topic has a ROS 2 type (left out: {})",
            file.display(),
            if plan.left_out.is_empty() {
                "nothing recorded".to_string()
            } else {
                plan.left_out.join(", ")
            }
        )));
    }
    Ok(plan)
}

/// `Ok(Err(_))` is bad input, `Err(_)` a failure to write.
fn run(args: &ExportArgs) -> Result<Result<(), Bad>> {
    let out = &args.out;
    if out.symlink_metadata().is_ok() {
        return Ok(Err(Bad(anyhow!(
            "{} exists already; give a new directory for the bag",
            out.display()
        ))));
    }
    let recording = match read_recording(&args.file, &[]) {
        Ok(r) => r,
        Err(e) => return Ok(Err(Bad(e))),
    };
    let plan = match plan(&recording.types, &args.file) {
        Ok(p) => p,
        Err(bad) => return Ok(Err(bad)),
    };
    let mut bag = match BagWriter::create(out) {
        Ok(b) => b,
        Err(e) => return Ok(Err(Bad(e))),
    };
    // Whatever goes wrong from here, no half-written bag is left behind.
    let written = match write(&mut bag, &recording, &plan, &args.file) {
        Ok(()) => bag.finish().map_err(Fail::Io),
        Err(fail) => Err(fail),
    };
    let written = match written {
        Ok(w) => w,
        Err(fail) => {
            let _ = std::fs::remove_dir_all(out);
            return match fail {
                Fail::Bad(bad) => Ok(Err(bad)),
                Fail::Io(e) => Err(e),
            };
        }
    };
    if !plan.left_out.is_empty() {
        eprintln!(
            "caravan: left out (no ROS 2 type): {}",
            plan.left_out.join(", ")
        );
    }
    summary(&written, out);
    Ok(Ok(()))
}

enum Fail {
    Bad(Bad),
    Io(anyhow::Error),
}

fn write(
    bag: &mut BagWriter,
    recording: &caravan_group::play::Recording,
    plan: &Plan,
    file: &Path,
) -> Result<(), Fail> {
    for (ros, ty) in plan.own.values() {
        // A map is latched, as map_server offers it; the rest as ROS 2's default.
        let qos = if *ty == RosType::OccupancyGrid {
            offered_qos(true, 1)
        } else {
            offered_qos(false, 10)
        };
        bag.add_topic(ros, *ty, &qos).map_err(Fail::Io)?;
    }
    if !plan.tf.is_empty() {
        // As tf2's broadcasters offer it.
        bag.add_topic(TF_TOPIC, RosType::TfMessage, &offered_qos(false, 100))
            .map_err(Fail::Io)?;
    }
    // In stamp order: the bag's log time is the stamp (realtime recordings log the wall clock).
    let mut messages: Vec<&caravan_group::play::Recorded> = recording.messages.iter().collect();
    messages.sort_by_key(|m| m.stamp_ns);
    let mut counts: BTreeMap<&str, u64> = BTreeMap::new();
    for m in messages {
        let own = plan.own.get(&m.topic);
        if own.is_none() && !plan.tf.contains(&m.topic) {
            continue;
        }
        let n = counts.entry(&m.topic).or_insert(0);
        *n += 1;
        let caravan_type = &recording.types[&m.topic];
        let exported = convert(&m.topic, caravan_type, &m.json, m.stamp_ns).map_err(|e| {
            Fail::Bad(Bad(anyhow!(
                "{}: message {n} on {} ({caravan_type}) does not convert: {e}",
                file.display(),
                m.topic
            )))
        })?;
        if let (Some((ros, _)), Some(message)) = (own, &exported.own) {
            bag.write_message(ros, m.stamp_ns, message)
                .map_err(Fail::Io)?;
        }
        if let Some(tf) = &exported.tf {
            bag.write_message(TF_TOPIC, m.stamp_ns, tf)
                .map_err(Fail::Io)?;
        }
    }
    Ok(())
}

fn summary(written: &Written, out: &Path) {
    let width = written
        .topics
        .iter()
        .map(|(t, _, _)| t.len())
        .max()
        .unwrap_or(0);
    for (topic, ty, count) in &written.topics {
        println!("{topic:<width$}  {:<32} {count:>7}", ty.name());
    }
    println!(
        "exported {} messages on {} topics to {} (rosbag2, MCAP storage: {})",
        written.messages,
        written.topics.len(),
        out.display(),
        written.file.display()
    );
}
