//! `caravan record`: records a running group's topics to an MCAP file.

use anyhow::Result;
use caravan_group::clean::choose_group;
use caravan_group::watch::{GroupArg, seconds_arg};
use clap::Args;

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
    #[arg(long, value_parser = seconds_arg)]
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
    let recording = caravan_group::watch::record(&group, &args.output, &patterns, args.seconds)?;
    let total: u64 = recording
        .topics
        .values()
        .map(|t| t.counted.count().messages)
        .sum();
    println!(
        "recorded {total} messages on {} topics to {}",
        recording.topics.len(),
        args.output.display()
    );
    Ok(())
}
