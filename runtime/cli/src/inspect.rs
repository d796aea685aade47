//! `caravan topic …` and `caravan node …`: looking into a running group.

use anyhow::Result;
use caravan::tap::list_topics;
use caravan_group::clean::{choose_group, live_nodes};
use caravan_group::watch::{GroupArg, follow, seconds_arg};
use clap::{Args, Subcommand};
use std::time::{Duration, Instant};

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
    Pub(caravan_group::inject::PubArgs),
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
                    let header = caravan_record::schema::header_json(header, true);
                    fields.insert("header".into(), header);
                }
                println!("{json}");
                printed += 1;
                count.is_some_and(|c| printed >= c)
            })
        }
        TopicCommand::Pub(args) => caravan_group::inject::publish(&args),
        TopicCommand::Info { topic, group, json } => {
            caravan_group::graph::topic_info(&choose_group(group.group.as_deref())?, &topic, json)
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
            caravan_group::graph::node_info(&choose_group(group.group.as_deref())?, &name, json)
        }
    }
}
