//! `caravan topic …` and `caravan node …`: looking into a running group.

use crate::clean::{choose_group, live_nodes};
use anyhow::{Result, anyhow};
use caravan::tap::{list_topics, open_listener, open_tap};
use clap::{Args, Subcommand};
use iceoryx2::prelude::*;
use std::time::{Duration, Instant};

/// A `--seconds` value: finite, more than 0, at most ten years.
pub fn seconds_arg(text: &str) -> Result<Duration, String> {
    let value: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a number of seconds"))?;
    if value <= 0.0 {
        return Err(format!("'{text}': must be more than 0 seconds"));
    }
    caravan::seconds(value)
}

#[derive(Args)]
pub struct GroupArg {
    /// The group; defaults to the only running one
    #[arg(long, short, value_parser = crate::clean::group_arg)]
    pub group: Option<String>,
}

/// A list command's arguments.
#[derive(Args)]
pub struct ListArgs {
    #[command(flatten)]
    pub group: GroupArg,
    /// Print a JSON array instead of a table
    #[arg(long)]
    pub json: bool,
}

#[derive(Subcommand)]
pub enum TopicCommand {
    /// List the group's topics with their message types
    List(ListArgs),
    /// Print messages of a topic as JSON lines
    Echo {
        topic: String,
        #[command(flatten)]
        group: GroupArg,
        /// Stop after this many messages (at least 1)
        #[arg(long, short = 'n', value_parser = clap::value_parser!(u64).range(1..))]
        count: Option<u64>,
    },
    /// Show a topic's type, delivery contract, publishers and subscribers
    Info {
        topic: String,
        #[command(flatten)]
        group: GroupArg,
        /// Print JSON instead of text
        #[arg(long)]
        json: bool,
    },
    /// Publish a message (JSON) on a topic, once or at a rate
    Pub(crate::inject::PubArgs),
    /// Measure a topic's publishing rate
    Hz {
        topic: String,
        #[command(flatten)]
        group: GroupArg,
        /// Measure for this many seconds
        #[arg(long, default_value = "5", value_parser = seconds_arg)]
        seconds: Duration,
    },
}

#[derive(Subcommand)]
pub enum NodeCommand {
    /// List the group's live nodes
    List(ListArgs),
    /// Show a node's process, the topics it publishes and subscribes, and its last status
    Info {
        name: String,
        #[command(flatten)]
        group: GroupArg,
        /// Print JSON instead of text
        #[arg(long)]
        json: bool,
    },
}

pub fn iox(group: &str) -> Result<(iceoryx2::config::Config, iceoryx2::node::Node<ipc::Service>)> {
    let config = caravan::group::config(group)?;
    let node = NodeBuilder::new()
        .config(&config)
        .signal_handling_mode(SignalHandlingMode::HandleTerminationRequests)
        .create::<ipc::Service>()
        .map_err(|e| anyhow!("cannot join group '{group}': {e:?}"))?;
    Ok((config, node))
}

pub fn topic(cmd: TopicCommand) -> Result<()> {
    match cmd {
        TopicCommand::List(args) => {
            let group = choose_group(args.group.group.as_deref())?;
            let topics = list_topics(&caravan::group::config(&group)?, false)?;
            if args.json {
                let rows: Vec<serde_json::Value> = topics
                    .iter()
                    .map(|t| {
                        serde_json::json!({"name": t.name, "type": t.type_name,
                            "payload_bytes": t.payload_size, "nodes": t.nodes})
                    })
                    .collect();
                println!("{}", serde_json::Value::from(rows));
                return Ok(());
            }
            for t in topics {
                println!(
                    "{:<32} {:<28} {:>9} B  {} nodes",
                    t.name, t.type_name, t.payload_size, t.nodes
                );
            }
            Ok(())
        }
        TopicCommand::Echo {
            topic,
            group,
            count,
        } => {
            let group = choose_group(group.group.as_deref())?;
            let mut printed = 0;
            follow(&group, &topic, None, |header, mut json| {
                // The recording's shape: the message's fields and its header.
                if let serde_json::Value::Object(fields) = &mut json {
                    let header = crate::record::schema::header_json(header, true);
                    fields.insert("header".into(), header);
                }
                println!("{json}");
                printed += 1;
                count.is_some_and(|c| printed >= c)
            })
        }
        TopicCommand::Pub(args) => crate::inject::publish(&args),
        TopicCommand::Info { topic, group, json } => {
            crate::graph::topic_info(&choose_group(group.group.as_deref())?, &topic, json)
        }
        TopicCommand::Hz {
            topic,
            group,
            seconds,
        } => {
            let group = choose_group(group.group.as_deref())?;
            let started = Instant::now();
            let mut n = 0u64;
            follow(&group, &topic, Some(seconds), |_, _| {
                n += 1;
                false
            })?;
            let secs = started.elapsed().as_secs_f64();
            println!(
                "{topic}: {n} messages in {secs:.2} s = {:.2} Hz",
                n as f64 / secs
            );
            Ok(())
        }
    }
}

/// Notices that a group has ended (no process of it but this one is alive), looking at most
/// once a second: listing nodes is too dear for every message.
pub struct GroupEnd {
    group: String,
    last_look: Instant,
}

impl GroupEnd {
    pub fn watch(group: &str) -> Self {
        Self {
            group: group.to_string(),
            last_look: Instant::now(),
        }
    }

    /// Whether the group has ended, if a second has passed since the last look; else false.
    pub fn ended(&mut self) -> Result<bool> {
        if self.last_look.elapsed() < Duration::from_secs(1) {
            return Ok(false);
        }
        self.last_look = Instant::now();
        let me = std::process::id() as i32;
        Ok(!live_nodes(&self.group)?.iter().any(|n| n.pid != me))
    }
}

/// Calls `each` for every message on `topic` until it returns true, `limit` passes, the group
/// ends (looked at once a second) or Ctrl-C.
pub fn follow(
    group: &str,
    topic: &str,
    limit: Option<Duration>,
    mut each: impl FnMut(&caravan::Header, serde_json::Value) -> bool,
) -> Result<()> {
    let (config, node) = iox(group)?;
    let info = list_topics(&config, true)?
        .into_iter()
        .find(|t| t.name == topic)
        .ok_or_else(|| anyhow!("group '{group}' has no topic '{topic}'"))?;
    let tap = open_tap(&node, topic, &info.type_name)?;
    let listener = open_listener(&node, topic)?;
    let waitset = WaitSetBuilder::new()
        .signal_handling_mode(SignalHandlingMode::HandleTerminationRequests)
        .create::<ipc::Service>()
        .map_err(|e| anyhow!("{e:?}"))?;
    let _guard = waitset
        .attach_notification(&listener)
        .map_err(|e| anyhow!("{e:?}"))?;
    let end = limit.map(|l| Instant::now() + l);
    let mut batch = Vec::new();
    let mut group_end = GroupEnd::watch(group);
    loop {
        let wait = end.map_or(Duration::from_secs(1), |e| {
            e.saturating_duration_since(Instant::now())
                .min(Duration::from_secs(1))
        });
        let result = waitset
            .wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, wait)
            .map_err(|e| anyhow!("{e:?}"))?;
        if !matches!(
            result,
            iceoryx2::waitset::WaitSetRunResult::AllEventsHandled
        ) {
            return Ok(());
        }
        let _ = listener.try_wait(|_| {});
        // Looked at before draining, so that what was published before the end is printed.
        let ended = group_end.ended()?;
        tap.drain(&mut batch)?;
        for m in batch.drain(..) {
            if each(&m.header, m.json()?) {
                return Ok(());
            }
        }
        if end.is_some_and(|e| Instant::now() >= e) {
            return Ok(());
        }
        if ended {
            eprintln!("caravan: group '{group}' has ended");
            return Ok(());
        }
    }
}

pub fn node(cmd: NodeCommand) -> Result<()> {
    match cmd {
        NodeCommand::List(args) => {
            let group = choose_group(args.group.group.as_deref())?;
            let nodes = live_nodes(&group)?;
            if args.json {
                let rows: Vec<serde_json::Value> = nodes
                    .iter()
                    .map(|n| serde_json::json!({"name": n.name, "pid": n.pid}))
                    .collect();
                println!("{}", serde_json::Value::from(rows));
                return Ok(());
            }
            for n in nodes {
                println!(
                    "{:<24} pid {}",
                    if n.name.is_empty() {
                        "(launcher)"
                    } else {
                        &n.name
                    },
                    n.pid
                );
            }
            Ok(())
        }
        NodeCommand::Info { name, group, json } => {
            crate::graph::node_info(&choose_group(group.group.as_deref())?, &name, json)
        }
    }
}
