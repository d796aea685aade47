//! Publishing into a running group from outside it: `caravan topic pub` (one message, at a
//! rate, as `ros2 topic pub`). `caravan play` shares its pieces.

use crate::bad_input::bad;
use crate::clean::choose_group;
use crate::watch::{GroupArg, GroupEnd, iox};
use anyhow::Result;
use caravan::inject::open_injector;
use caravan::tap::list_topics;
use caravan::{Delivery, Header};
use clap::Args;
use serde_json::Value;
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
pub(crate) fn source_id(what: &str) -> u64 {
    caravan_schemas::lockstep::name_hash(what)
}

/// The type of `topic` in the running group, or `given`; an error when they differ.
fn topic_type(group: &str, topic: &str, given: Option<&str>) -> Result<String> {
    let found = list_topics(&caravan::group::config(group)?, true)?
        .into_iter()
        .find(|t| t.name == topic)
        .map(|t| t.type_name);
    match (found, given) {
        (Some(found), Some(given)) if found != given => Err(bad(format!(
            "topic '{topic}' carries {found} in group '{group}', not {given}"
        ))),
        (Some(found), _) => Ok(found),
        (None, Some(given)) => Ok(given.to_string()),
        (None, None) => Err(bad(format!(
            "group '{group}' has no topic '{topic}'; give its type with --type to create it"
        ))),
    }
}

pub fn publish(args: &PubArgs) -> Result<()> {
    let group = choose_group(args.group.group.as_deref())?;
    let json: Value = serde_json::from_str(&args.message)
        .map_err(|e| bad(format!("the message is not JSON: {e}")))?;
    let type_name = topic_type(&group, &args.topic, args.type_name.as_deref())?;
    // Checked before joining the group, so a bad message leaves nothing behind.
    let descriptor = caravan::types::lookup(&caravan::group::config(&group)?, &type_name)
        .map_err(|e| bad(format!("{e:#}")))?;
    descriptor
        .default_bytes()
        .and_then(|mut bytes| descriptor.write(&json, &mut bytes))
        .map_err(|e| bad(format!("{type_name}: {e}")))?;
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
pub(crate) fn sleep_until(
    node: &iceoryx2::node::Node<iceoryx2::prelude::ipc::Service>,
    when: Instant,
) -> bool {
    let left = when.saturating_duration_since(Instant::now());
    node.wait(left).is_ok()
}
