//! `caravan topic info` and `caravan node info`: who publishes and who subscribes what, read
//! from the group's shared-memory services (as `ros2 topic info -v` and `ros2 node info`).

use crate::bad_input::bad;
use crate::clean::{LiveNode, live_nodes};
use crate::watch::{follow, iox};
use anyhow::Result;
use caravan::tap::{TopicInfo, TopicPorts, list_topics, topic_ports};
use serde_json::{Value, json};
use std::time::Duration;

/// How long `node info` waits for the node's status (nodes publish one a second).
const STATUS_WAIT: Duration = Duration::from_millis(2500);

/// The group's topics with their ports, and its live nodes.
struct Graph {
    nodes: Vec<LiveNode>,
    topics: Vec<(TopicInfo, TopicPorts)>,
}

impl Graph {
    fn read(group: &str) -> Result<Self> {
        let (config, node) = iox(group)?;
        let mut topics = Vec::new();
        for info in list_topics(&config, false)? {
            // A topic whose last port went away between listing and opening is skipped.
            if let Ok(ports) = topic_ports(&node, &info.name, &info.type_name) {
                topics.push((info, ports));
            }
        }
        Ok(Graph {
            nodes: live_nodes(group)?,
            topics,
        })
    }

    /// The live node `name`; an error lists those there are.
    fn node(&self, group: &str, name: &str) -> Result<&LiveNode> {
        self.nodes.iter().find(|n| n.name == name).ok_or_else(|| {
            let names: Vec<&str> = self
                .nodes
                .iter()
                .map(|n| n.name.as_str())
                .filter(|n| !n.is_empty())
                .collect();
            let hint = caravan_launch::suggest::hint(name, &names);
            bad(format!("group '{group}' has no live node '{name}'{hint}"))
        })
    }

    /// The topics node `name` publishes, and those it subscribes to.
    fn topics_of(&self, group: &str, name: &str) -> Result<(Vec<&TopicInfo>, Vec<&TopicInfo>)> {
        let node = self.node(group, name)?;
        let on = |pick: fn(&TopicPorts) -> &Vec<iceoryx2::identifiers::UniqueNodeId>| {
            self.topics
                .iter()
                .filter(|(_, p)| pick(p).contains(&node.id))
                .map(|(t, _)| t)
                .collect()
        };
        Ok((on(|p| &p.publishers), on(|p| &p.subscribers)))
    }

    /// How a node is named: its process name, or the Caravan tool (launcher, recorder, an
    /// inspecting command) with its pid.
    fn name_of(&self, id: &iceoryx2::identifiers::UniqueNodeId) -> Value {
        match self.nodes.iter().find(|n| &n.id == id) {
            Some(n) if !n.name.is_empty() => json!({"node": n.name, "pid": n.pid}),
            Some(n) => json!({"node": "(caravan)", "pid": n.pid}),
            None => json!({"node": "(gone)", "pid": null}),
        }
    }
}

fn endpoint_line(e: &Value) -> String {
    match e["pid"].as_i64() {
        Some(pid) => format!("    {} (pid {pid})", e["node"].as_str().unwrap_or("?")),
        None => format!("    {}", e["node"].as_str().unwrap_or("?")),
    }
}

pub fn topic_info(group: &str, topic: &str, as_json: bool) -> Result<()> {
    let graph = Graph::read(group)?;
    let (info, ports) = graph
        .topics
        .iter()
        .find(|(t, _)| t.name == topic)
        .ok_or_else(|| bad(format!("group '{group}' has no topic '{topic}'")))?;
    let publishers: Vec<Value> = ports.publishers.iter().map(|i| graph.name_of(i)).collect();
    let subscribers: Vec<Value> = ports.subscribers.iter().map(|i| graph.name_of(i)).collect();
    let delivery = if ports.lossless { "lossless" } else { "latest" };
    if as_json {
        let out = json!({"name": info.name, "type": info.type_name,
            "payload_bytes": info.payload_size, "delivery": delivery, "depth": ports.depth,
            "publishers": publishers, "subscribers": subscribers});
        println!("{out}");
        return Ok(());
    }
    println!("Topic: {}", info.name);
    println!("Type: {} ({} B)", info.type_name, info.payload_size);
    println!(
        "Delivery: {delivery}, {} messages per subscriber",
        ports.depth
    );
    println!("Publishers: {}", publishers.len());
    publishers
        .iter()
        .for_each(|e| println!("{}", endpoint_line(e)));
    println!("Subscribers: {}", subscribers.len());
    subscribers
        .iter()
        .for_each(|e| println!("{}", endpoint_line(e)));
    Ok(())
}

/// The topics node `name` of `group` publishes and those it subscribes to.
pub fn topics_of(group: &str, name: &str) -> Result<(Vec<String>, Vec<String>)> {
    let graph = Graph::read(group)?;
    let names = |topics: Vec<&TopicInfo>| -> Vec<String> {
        topics.iter().map(|t| t.name.clone()).collect()
    };
    let (publishes, subscribes) = graph.topics_of(group, name)?;
    Ok((names(publishes), names(subscribes)))
}

pub fn node_info(group: &str, name: &str, as_json: bool) -> Result<()> {
    let graph = Graph::read(group)?;
    let node = graph.node(group, name)?;
    let listed = |topics: Vec<&TopicInfo>| -> Vec<Value> {
        topics
            .iter()
            .map(|t| json!({"name": t.name, "type": t.type_name}))
            .collect()
    };
    let (publishes, subscribes) = graph.topics_of(group, name)?;
    let (publishes, subscribes) = (listed(publishes), listed(subscribes));
    let mut status = Value::Null;
    follow(group, "status", Some(STATUS_WAIT), |_, s| {
        let mine = s["node"] == name;
        if mine {
            status = s;
        }
        mine
    })?;
    if as_json {
        let out = json!({"name": name, "pid": node.pid, "publishes": publishes,
            "subscribes": subscribes, "status": status});
        println!("{out}");
        return Ok(());
    }
    println!("Node: {name} (pid {})", node.pid);
    let topic_line = |t: &Value| format!("    {}: {}", t["name"], t["type"]).replace('"', "");
    println!("Publishes: {}", publishes.len());
    publishes.iter().for_each(|t| println!("{}", topic_line(t)));
    println!("Subscribes: {}", subscribes.len());
    subscribes
        .iter()
        .for_each(|t| println!("{}", topic_line(t)));
    match status.as_object() {
        Some(fields) => {
            println!("Status:");
            for (k, v) in fields.iter().filter(|(k, _)| !k.starts_with('_')) {
                println!("    {k}: {}", v.to_string().trim_matches('"'));
            }
        }
        None => println!(
            "Status: none in {:.1} s (a lockstep group that is not advancing publishes none)",
            STATUS_WAIT.as_secs_f64()
        ),
    }
    Ok(())
}
