//! `caravan info FILE.mcap`: what a recording holds, from its summary (as `ros2 bag info` and
//! `mcap info` print): time span, messages, channels with schema and count, the run's metadata
//! and attachments. A file without a summary (cut short by a crash) is read through instead.
//!
//! Either way every message is read once, with each chunk's CRC checked, and the count must
//! match the summary's: a damaged file is refused (exit 2), as `play` and `resim` refuse it,
//! rather than described from a summary that no longer holds.

use anyhow::Result;
use caravan_group::info::describe;
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct InfoArgs {
    /// The recording (a run directory's record.mcap)
    pub file: PathBuf,
    /// Print JSON instead of a table
    #[arg(long)]
    pub json: bool,
}

/// Prints what the recording holds; returns the exit code (2: the file cannot be read, is
/// not MCAP, or is damaged).
pub fn info(args: &InfoArgs) -> Result<u8> {
    let file = args.file.display();
    let bytes = match caravan::input::map_recording(&args.file) {
        Ok(b) => b,
        Err(e) => return Ok(refuse(format!("cannot read {file}: {e:#}"))),
    };
    if !bytes.starts_with(mcap::MAGIC) {
        return Ok(refuse(format!("{file} is not an MCAP file")));
    }
    let facts = match describe(&bytes) {
        Ok(f) => f,
        Err(e) => return Ok(refuse(format!("{file}: {e:#}"))),
    };
    if args.json {
        println!("{facts:#}");
        return Ok(0);
    }
    println!("file:        {}", args.file.display());
    println!(
        "messages:    {} in {:.3} s{}",
        facts["messages"],
        facts["duration_s"].as_f64().unwrap_or(0.0),
        if facts["indexed"] == true {
            ""
        } else {
            " (no summary: read through)"
        }
    );
    for (name, m) in facts["metadata"].as_object().into_iter().flatten() {
        let pairs: Vec<String> = m
            .as_object()
            .into_iter()
            .flatten()
            .map(|(k, v)| format!("{k}={}", v.as_str().unwrap_or_default()))
            .collect();
        println!("metadata:    {name}: {}", pairs.join(", "));
    }
    for a in facts["attachments"].as_array().into_iter().flatten() {
        println!(
            "attachment:  {} ({}, {} B)",
            a["name"].as_str().unwrap_or(""),
            a["media_type"].as_str().unwrap_or(""),
            a["bytes"]
        );
    }
    let channels = facts["channels"].as_array().cloned().unwrap_or_default();
    let width = channels
        .iter()
        .map(|c| c["topic"].as_str().unwrap_or("").len())
        .max()
        .unwrap_or(5)
        .max(5);
    println!("channels:    {}", channels.len());
    for c in &channels {
        println!(
            "  {:width$}  {:>8}  {} ({})",
            c["topic"].as_str().unwrap_or(""),
            c["messages"],
            c["schema"].as_str().unwrap_or(""),
            c["encoding"].as_str().unwrap_or(""),
        );
    }
    println!("verified:    every chunk's CRC, and the message count");
    Ok(0)
}

fn refuse(message: String) -> u8 {
    eprintln!("caravan: {message}");
    caravan_group::launch::EXIT_BAD_INPUT
}
