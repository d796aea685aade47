//! A rosbag2 bag played as a recording: `caravan play BAG` and `caravan launch … --play BAG`
//! take a bag (a directory with `metadata.yaml`, or its `.mcap` file of profile `ros2`) of the
//! types Caravan maps, as `caravan export --ros2` writes one, and read it into the same
//! [`Recording`] a Caravan recording gives, so that playing works alike. Each ROS 2 topic
//! plays on its Caravan topic (`/robot_0/scan` on `robot/0/scan`) as the Caravan type it maps
//! back to (`caravan_ros2::inverse`); `/tf` and `/clock` are left out, since a group derives
//! them. A message's stamp is its header's (its log time when its type has no header); its
//! sequence number counts the topic's messages from 1; its source is the player.

use crate::inject::source_id;
use crate::recording::{Recorded, Recording};
use anyhow::{Context, Result, anyhow, bail};
use caravan_ros2::bag::read_bag;
use caravan_ros2::inverse::{caravan_json, caravan_topic, caravan_type_in};
use std::collections::BTreeMap;
use std::path::Path;

/// Reads the bag at `path`, the topics `patterns` select (all when empty), as a recording.
pub(crate) fn read_bag_recording(path: &Path, patterns: &[String]) -> Result<Recording> {
    let bag = read_bag(path)?;
    let at = path.display();
    let chosen = |topic: &str| crate::recording::selected(patterns, topic);
    let mut recording = Recording::default();
    // ROS topic → (Caravan topic, Caravan type) of the topics played.
    let mut played: BTreeMap<&str, (String, &'static str)> = BTreeMap::new();
    let mut from: BTreeMap<String, &str> = BTreeMap::new();
    for (ros, &ty) in &bag.topics {
        let topic = caravan_topic(ros);
        let Some(caravan_type) = caravan_type_in(ty, &topic) else {
            continue;
        };
        if let Some(other) = from.insert(topic.clone(), ros) {
            bail!("{at}: both {other} and {ros} would play on Caravan topic {topic}");
        }
        recording.topics.push(topic.clone());
        if chosen(&topic) {
            recording
                .types
                .insert(topic.clone(), caravan_type.to_string());
            played.insert(ros, (topic, caravan_type));
        }
    }
    let mut seq: BTreeMap<&str, u64> = BTreeMap::new();
    let source = source_id("play");
    for m in &bag.messages {
        let Some((topic, caravan_type)) = played.get(m.topic.as_str()) else {
            continue;
        };
        let n = seq.entry(m.topic.as_str()).or_insert(0);
        *n += 1;
        let message = caravan_json(m.ty, caravan_type, &m.cdr).map_err(|e| {
            anyhow!(
                "{at}: message {n} on {} ({}) cannot be played as a {caravan_type}: {e}",
                m.topic,
                m.ty.name()
            )
        })?;
        let stamp_ns = message.stamp_ns.unwrap_or(m.log_ns);
        let header = caravan::Header {
            seq: *n,
            stamp_ns,
            send_wall_ns: 0,
            source_id: source,
        };
        let mut json = message.json;
        json["header"] = caravan_record::schema::header_json(&header, false);
        let data = serde_json::to_vec(&json).context("a message as JSON")?;
        recording.messages.push(Recorded {
            log_ns: m.log_ns,
            topic: topic.clone(),
            seq: *n,
            stamp_ns,
            source_id: source,
            json,
            data,
        });
    }
    recording.topics.sort();
    Ok(recording)
}
