//! Publishing into a running group from outside it: `caravan topic pub` (one message, at a
//! rate, as `ros2 topic pub`) and `caravan play` (a recording's topics at their recorded
//! times, as `ros2 bag play`).

use crate::clean::choose_group;
use crate::inspect::{GroupArg, GroupEnd, iox};
use anyhow::{Context, Result, anyhow, bail};
use caravan::inject::{DynInject, open_injector};
use caravan::tap::list_topics;
use caravan::{Delivery, Header};
use clap::Args;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::{Duration, Instant};

#[derive(Args)]
pub struct PubArgs {
    /// The topic, e.g. robot/0/cmd_vel
    pub topic: String,
    /// The message as JSON in the recording's shape, e.g. '{"linear": {"x": 0.2}}'; fields
    /// left out keep their defaults
    pub message: String,
    /// The message type (e.g. caravan::Twist); defaults to the type of the topic in the group
    #[arg(long = "type", short = 't')]
    pub type_name: Option<String>,
    #[command(flatten)]
    pub group: GroupArg,
    /// Publishing rate in Hz
    #[arg(long, short, default_value = "1", value_parser = rate_arg)]
    pub rate: f64,
    /// Publish this many times, then exit (default: until Ctrl-C or the group ends)
    #[arg(long, short = 'n', value_parser = clap::value_parser!(u64).range(1..))]
    pub times: Option<u64>,
    /// Publish once and exit (same as -n 1)
    #[arg(long, conflicts_with = "times")]
    pub once: bool,
}

/// A rate in Hz: finite, above 0, at most 10 kHz.
fn rate_arg(text: &str) -> Result<f64, String> {
    match text.trim().trim_end_matches("Hz").parse::<f64>() {
        Ok(hz) if hz > 0.0 && hz <= 10_000.0 => Ok(hz),
        _ => Err(format!(
            "'{text}': expected a rate above 0 and at most 10000 Hz"
        )),
    }
}

/// The id a message published by this command carries as its source (a node's is a hash of
/// its name; this one is named for the command).
fn source_id(what: &str) -> u64 {
    caravan_schemas::lockstep::name_hash(what)
}

/// The type of `topic` in the running group, or `given`; an error when they differ.
fn topic_type(group: &str, topic: &str, given: Option<&str>) -> Result<String> {
    let found = list_topics(&caravan::group::config(group)?, true)?
        .into_iter()
        .find(|t| t.name == topic)
        .map(|t| t.type_name);
    match (found, given) {
        (Some(found), Some(given)) if found != given => {
            bail!("topic '{topic}' carries {found} in group '{group}', not {given}")
        }
        (Some(found), _) => Ok(found),
        (None, Some(given)) => Ok(given.to_string()),
        (None, None) => {
            bail!("group '{group}' has no topic '{topic}'; give its type with --type to create it")
        }
    }
}

pub fn publish(args: &PubArgs) -> Result<()> {
    let group = choose_group(args.group.group.as_deref())?;
    let json: Value =
        serde_json::from_str(&args.message).map_err(|e| anyhow!("the message is not JSON: {e}"))?;
    let type_name = topic_type(&group, &args.topic, args.type_name.as_deref())?;
    // Checked before joining the group, so a bad message leaves nothing behind.
    caravan_schemas::with_message_type!(type_name.as_str(), |T| {
        caravan_schemas::from_json::message_from_json::<T>(&json).map(|_| ())
    })
    .unwrap_or_else(|| Err(format!("unknown message type '{type_name}'")))
    .map_err(|e| anyhow!("{type_name}: {e}"))?;
    let (_config, node) = iox(&group)?;
    let injector = open_injector(
        &node,
        &args.topic,
        &type_name,
        Delivery::Latest { depth: 8 },
    )?;
    let times = if args.once { Some(1) } else { args.times };
    let period = Duration::from_secs_f64(1.0 / args.rate);
    let mut group_end = GroupEnd::watch(&group);
    let mut next = Instant::now();
    let mut seq = 0u64;
    loop {
        seq += 1;
        injector.publish_json(header(seq, 0, "topic-pub"), &json)?;
        if times.is_some_and(|t| seq >= t) || group_end.ended()? {
            return Ok(());
        }
        next += period;
        if !sleep_until(&node, next) {
            return Ok(());
        }
    }
}

fn header(seq: u64, stamp_ns: u64, source: &str) -> Header {
    Header {
        seq,
        stamp_ns,
        send_wall_ns: caravan::wall_clock_ns(),
        source_id: source_id(source),
    }
}

/// Sleeps until `when`; false when Ctrl-C or SIGTERM came first (iceoryx2's node wait
/// returns early on either).
fn sleep_until(
    node: &iceoryx2::node::Node<iceoryx2::prelude::ipc::Service>,
    when: Instant,
) -> bool {
    let left = when.saturating_duration_since(Instant::now());
    node.wait(left).is_ok()
}

#[derive(Args)]
pub struct PlayArgs {
    /// The recording (a run's record.mcap, or one made by `caravan record`)
    pub file: PathBuf,
    #[command(flatten)]
    pub group: GroupArg,
    /// Only these topics (as in the launch file's `record`: names or patterns with *)
    #[arg(long, num_args = 1..)]
    pub topics: Vec<String>,
    /// Playback speed: 2 plays twice as fast as recorded
    #[arg(long, default_value = "1", value_parser = speed_arg)]
    pub speed: f64,
}

fn speed_arg(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(s) if s > 0.0 && s <= 1000.0 => Ok(s),
        _ => Err(format!(
            "'{text}': expected a speed above 0 and at most 1000"
        )),
    }
}

/// One recorded message to play: when (ns since the recording's first), where and what.
struct Recorded {
    at_ns: u64,
    topic: String,
    json: Value,
}

/// The recording's Caravan channels (JSON, a registry type) that `patterns` select, with their
/// types, and their messages in time order.
fn read_recording(
    path: &std::path::Path,
    patterns: &[String],
) -> Result<(BTreeMap<String, String>, Vec<Recorded>)> {
    let bytes =
        caravan::input::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut types = BTreeMap::new();
    let mut messages = Vec::new();
    let at = || path.display().to_string();
    for message in mcap::MessageStream::new(&bytes).with_context(at)? {
        let message = message.with_context(at)?;
        let channel = &message.channel;
        let Some(schema) = channel.schema.as_ref() else {
            continue;
        };
        let caravan_type = caravan_schemas::message_type_names().contains(&schema.name.as_str());
        let chosen = patterns.is_empty()
            || patterns
                .iter()
                .any(|p| crate::launch::model::glob_match(p, &channel.topic));
        if channel.message_encoding != "json"
            || !caravan_type
            || !chosen
            || channel.topic == "status"
        {
            continue;
        }
        types.insert(channel.topic.clone(), schema.name.clone());
        messages.push(Recorded {
            at_ns: message.log_time,
            topic: channel.topic.clone(),
            json: serde_json::from_slice(&message.data)
                .with_context(|| format!("{}: a message on {} is not JSON", at(), channel.topic))?,
        });
    }
    messages.sort_by_key(|m| m.at_ns);
    Ok((types, messages))
}

pub fn play(args: &PlayArgs) -> Result<()> {
    let (types, messages) = read_recording(&args.file, &args.topics)?;
    if messages.is_empty() {
        bail!(
            "{}: no recorded Caravan messages to play{}",
            args.file.display(),
            if args.topics.is_empty() {
                String::new()
            } else {
                format!(" on {}", args.topics.join(", "))
            }
        );
    }
    let group = choose_group(args.group.group.as_deref())?;
    let (_config, node) = iox(&group)?;
    let mut injectors: BTreeMap<&str, Box<dyn DynInject>> = BTreeMap::new();
    for (topic, type_name) in &types {
        injectors.insert(
            topic,
            open_injector(&node, topic, type_name, Delivery::Latest { depth: 8 })?,
        );
    }
    let first = messages[0].at_ns;
    let start = Instant::now();
    let mut group_end = GroupEnd::watch(&group);
    let mut played = 0u64;
    for m in &messages {
        let due = start + Duration::from_secs_f64((m.at_ns - first) as f64 / 1e9 / args.speed);
        if !sleep_until(&node, due) || group_end.ended()? {
            break;
        }
        // The recorded header travels with the message, so subscribers see the original
        // sequence numbers, stamps and sources.
        let h = &m.json["header"];
        let header = Header {
            seq: caravan_report::as_u64(&h["seq"]).unwrap_or(played + 1),
            stamp_ns: caravan_report::as_u64(&h["stamp_ns"]).unwrap_or(m.at_ns),
            send_wall_ns: caravan::wall_clock_ns(),
            source_id: caravan_report::as_u64(&h["source_id"]).unwrap_or_else(|| source_id("play")),
        };
        injectors[m.topic.as_str()].publish_json(header, &m.json)?;
        played += 1;
    }
    eprintln!(
        "caravan: played {played} of {} messages on {} topics into group '{group}'",
        messages.len(),
        types.len()
    );
    Ok(())
}
