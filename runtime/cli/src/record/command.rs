//! `caravan record`: records a running group's topics to an MCAP file.

use crate::clean::choose_group;
use crate::inspect::GroupArg;
use anyhow::Result;
use clap::Args;
use iceoryx2::prelude::*;
use std::time::Instant;

#[derive(Args)]
pub struct RecordArgs {
    /// Topic patterns (`*` one segment, `**` any); default all topics
    #[arg(value_parser = clap::builder::NonEmptyStringValueParser::new())]
    pub patterns: Vec<String>,
    /// Output MCAP file
    #[arg(short, long)]
    pub output: std::path::PathBuf,
    #[command(flatten)]
    pub group: GroupArg,
    /// Stop after this many seconds (default: until Ctrl-C)
    #[arg(long, value_parser = crate::inspect::seconds_arg)]
    pub seconds: Option<std::time::Duration>,
}

/// `caravan record`: records a running group's topics until Ctrl-C.
pub fn record(args: RecordArgs) -> Result<()> {
    let group = choose_group(args.group.group.as_deref())?;
    let patterns = if args.patterns.is_empty() {
        vec!["**".to_string()]
    } else {
        args.patterns
    };
    let mut recorder = crate::record::Recorder::create(
        &caravan::group::config(&group)?,
        &args.output,
        &patterns,
        false,
        &crate::record::recorder::RecordingMeta {
            metadata: crate::record::recorder::run_metadata(None, Some(caravan::wall_clock_ns())),
            launch_file: None,
        },
    )?;
    let end = args.seconds.map(|s| Instant::now() + s);
    let config = caravan::group::config(&group)?;
    let mut group_end = crate::inspect::GroupEnd::watch(&group);
    let mut ended = false;
    crate::run::driver::record_until(
        &config,
        &mut recorder,
        SignalHandlingMode::HandleTerminationRequests,
        |_| {
            // The group's end stops the recording too.
            ended = ended || group_end.ended().unwrap_or(false);
            ended || end.is_some_and(|e| Instant::now() >= e)
        },
    )?;
    if ended {
        eprintln!("caravan: group '{group}' has ended");
    }
    let recording = recorder.finish()?;
    let total: u64 = recording.topics.values().map(|t| t.messages).sum();
    println!(
        "recorded {total} messages on {} topics to {}",
        recording.topics.len(),
        args.output.display()
    );
    Ok(())
}
