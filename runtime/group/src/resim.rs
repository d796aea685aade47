//! `caravan resim RECORDING --node NAME`: deterministic re-simulation of one node.
//!
//! The recording's resolved launch file (its `launch.toml` attachment) is launched again with
//! only the node under test, in lockstep, and the player (`caravan launch --play`) stands in
//! for the rest of the group: every message the node did not publish itself reaches it at
//! the simulated time, with the header, it did when recorded. The node's new outputs are then
//! compared byte for byte with its recorded ones. Caravan's own nodes are deterministic, so
//! they match exactly; a difference points at the node (or a change given with `--set`), not
//! at the rest of the group. rosbag2 replays topics but cannot promise this.

use crate::launch::{EXIT_BAD_INPUT, Launched, RunOptions, start};
use crate::play::{InGroup, Recorded, read_recording};
use crate::run::LAUNCH_FILE_KEY;
use anyhow::{Context, Result, anyhow, bail};
use caravan_launch::model::LaunchFile;
use caravan_schemas::lockstep::name_hash;
use clap::Args;
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct ResimArgs {
    /// A lockstep recording made by `caravan launch` (a run's record.mcap)
    pub file: PathBuf,
    /// The node to run again; the recording must hold its outputs and every topic it reads
    #[arg(long)]
    pub node: String,
    /// Where the recorded launch file's relative paths start (default: the directory of the
    /// launch file the run was started with, as recorded, from the current directory)
    #[arg(long, value_name = "DIR")]
    pub launch_dir: Option<PathBuf>,
    /// Change the launch file before the rerun, e.g. `process.slam.params.resolution=0.1`:
    /// the comparison then shows what the change did to the node's outputs
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Directory that receives the rerun's run directory
    #[arg(long, default_value = "runs")]
    pub runs_dir: PathBuf,
    /// Do not echo process output to the terminal
    #[arg(long)]
    pub quiet: bool,
    /// Print the comparison as JSON
    #[arg(long)]
    pub json: bool,
}

/// The comparison's file in the rerun's run directory.
const RESULT_FILE: &str = "resim.json";

pub fn resim(args: &ResimArgs) -> Result<u8> {
    let (lf, original) = match prepare(args) {
        Ok(prepared) => prepared,
        Err(e) => {
            eprintln!("caravan: {e:#}");
            return Ok(EXIT_BAD_INPUT);
        }
    };
    let options = RunOptions {
        runs_dir: args.runs_dir.clone(),
        quiet: args.quiet,
        foxglove: None,
        play: Some(InGroup {
            file: args.file.clone(),
            topics: Vec::new(),
            under_test: Some(args.node.clone()),
        }),
        only: vec![args.node.clone()],
        host: None,
        arguments: caravan_record::recorder::command_arguments(),
    };
    let Launched { code, dir } = start(lf, &options)?;
    let Some(dir) = dir else {
        return Ok(code);
    };
    if code != 0 {
        eprintln!(
            "caravan: the rerun of '{}' failed; its logs are in {}",
            args.node,
            dir.join("logs").display()
        );
        return Ok(code);
    }
    let rerun = read_recording(&dir.join(caravan_report::RECORDING_FILE), &[])?;
    let mut result = compare(&args.node, &original, &rerun.messages);
    result["run_dir"] = json!(dir.display().to_string());
    std::fs::write(
        dir.join(RESULT_FILE),
        serde_json::to_string_pretty(&result)?,
    )?;
    let identical = result["identical"] == true;
    if args.json {
        println!("{result}");
    } else {
        print_result(&result, &dir);
    }
    Ok(if identical { 0 } else { 1 })
}

/// The launch file to rerun, with only what the rerun records, and the recorded messages.
fn prepare(args: &ResimArgs) -> Result<(LaunchFile, Vec<Recorded>)> {
    let file = &args.file;
    let bytes = caravan::input::map_recording(file)
        .with_context(|| format!("cannot read {}", file.display()))?;
    let (text, recorded_path) = attached_launch_file(file, &bytes)?;
    let launch_dir = match &args.launch_dir {
        Some(dir) => dir.clone(),
        None => recorded_path
            .parent()
            .unwrap_or(Path::new(""))
            .to_path_buf(),
    };
    if !launch_dir.as_os_str().is_empty() && !launch_dir.is_dir() {
        bail!(
            "{} was recorded from {}, whose directory {} is not here; give the directory the \
             launch file's relative paths start from with --launch-dir",
            file.display(),
            recorded_path.display(),
            launch_dir.display()
        );
    }
    let name = recorded_path
        .file_name()
        .map_or_else(|| "launch.toml".into(), |n| n.to_os_string());
    let original = read_recording(file, &[])?.messages;
    let source = name_hash(&args.node);
    let mut outputs: Vec<&str> = original
        .iter()
        .filter(|m| m.source_id == source)
        .map(|m| m.topic.as_str())
        .collect();
    outputs.sort();
    outputs.dedup();
    if outputs.is_empty() {
        bail!(
            "{} holds no message that node '{}' published; record its outputs (the group's \
             `record`) to compare them",
            file.display(),
            args.node
        );
    }
    // The rerun records the node's outputs only, under a name of its own.
    let mut sets = vec![
        format!("group.name=resim-{}", std::process::id()),
        format!("group.record={}", serde_json::to_string(&outputs)?),
    ];
    sets.extend(args.set.iter().cloned());
    let mut lf = caravan_launch::load::load_source(
        &launch_dir.join(name),
        Some(text),
        &sets,
        &crate::run::exec::resolve_exec,
        &crate::run::preflight::check_processes,
    )
    .map_err(|e| anyhow!("the launch file attached to {}: {e}", file.display()))?;
    // The scenario's report plugins judge whole runs; a rerun of one node is judged by the
    // comparison.
    lf.reports.clear();
    if lf.group.clock != caravan::ClockMode::Lockstep {
        bail!(
            "{} was recorded in realtime; only lockstep runs can be re-simulated exactly",
            file.display()
        );
    }
    Ok((lf, original))
}

/// The launch file attached to the recording `bytes` (read from `file`, named in errors) and
/// the path it was launched from, as the run's metadata records it (`launch.toml` when it
/// does not): what `caravan resim` reruns. An error for a file without a summary or without
/// the attachment, or whose records the summary points at are damaged.
pub fn attached_launch_file(file: &Path, bytes: &[u8]) -> Result<(String, PathBuf)> {
    caravan_report::guarded(file.display(), || attached_unguarded(file, bytes))
}

fn attached_unguarded(file: &Path, bytes: &[u8]) -> Result<(String, PathBuf)> {
    let summary = mcap::Summary::read(bytes)
        .ok()
        .flatten()
        .ok_or_else(|| anyhow!("{}: not an MCAP file with a summary", file.display()))?;
    let attached = summary
        .attachment_indexes
        .iter()
        .find(|a| a.name == caravan_report::RESOLVED_LAUNCH_FILE)
        .ok_or_else(|| {
            anyhow!(
                "{} has no launch file attached; only recordings made by `caravan launch` can \
                 be re-simulated",
                file.display()
            )
        })?;
    let text = String::from_utf8(mcap::read::attachment(bytes, attached)?.data.into_owned())
        .context("the attached launch file is not UTF-8")?;
    let mut recorded_path = None;
    for index in &summary.metadata_indexes {
        let m = mcap::read::metadata(bytes, index)?;
        if let Some(p) = m.metadata.get(LAUNCH_FILE_KEY) {
            recorded_path = Some(PathBuf::from(p));
        }
    }
    let recorded_path = recorded_path.unwrap_or_else(|| PathBuf::from("launch.toml"));
    Ok((text, recorded_path))
}

/// Compares what `node` published in the recording with what it published in the rerun, up
/// to the recording's end (a rerun may go on a little longer), topic by topic.
fn compare(node: &str, original: &[Recorded], rerun: &[Recorded]) -> Value {
    let source = name_hash(node);
    let end = original.iter().map(|m| m.log_ns).max().unwrap_or(0);
    let mut by_topic: BTreeMap<&str, (Vec<&Recorded>, Vec<&Recorded>)> = BTreeMap::new();
    for m in original.iter().filter(|m| m.source_id == source) {
        by_topic.entry(&m.topic).or_default().0.push(m);
    }
    for m in rerun
        .iter()
        .filter(|m| m.source_id == source && m.log_ns <= end)
    {
        by_topic.entry(&m.topic).or_default().1.push(m);
    }
    let mut topics = Vec::new();
    let mut identical = true;
    for (topic, (before, after)) in by_topic {
        let same =
            before.len() == after.len() && before.iter().zip(&after).all(|(a, b)| a.data == b.data);
        identical &= same;
        let mut entry = json!({"topic": topic, "recorded": before.len(),
            "resimulated": after.len(), "identical": same});
        if !same {
            entry["first_difference"] = first_difference(&before, &after);
        }
        topics.push(entry);
    }
    json!({"node": node, "identical": identical, "until_ns": end, "topics": topics})
}

/// Where two message sequences first part: the message's index and stamp, and the first
/// field that differs.
fn first_difference(before: &[&Recorded], after: &[&Recorded]) -> Value {
    let index = before
        .iter()
        .zip(after)
        .position(|(a, b)| a.data != b.data)
        .unwrap_or(before.len().min(after.len()));
    match (before.get(index), after.get(index)) {
        (Some(a), Some(b)) => {
            let (field, was, now) = field_difference(&a.json, &b.json, String::new())
                .unwrap_or_else(|| ("(encoding)".into(), Value::Null, Value::Null));
            json!({"index": index, "stamp_ns": a.stamp_ns, "field": field,
                   "recorded": was, "resimulated": now})
        }
        (Some(a), None) => json!({"index": index, "stamp_ns": a.stamp_ns,
                                  "field": "(missing in the rerun)"}),
        (None, Some(b)) => json!({"index": index, "stamp_ns": b.stamp_ns,
                                  "field": "(not in the recording)"}),
        (None, None) => Value::Null,
    }
}

/// The path of the first leaf where `a` and `b` differ, with both values.
fn field_difference(a: &Value, b: &Value, at: String) -> Option<(String, Value, Value)> {
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => x.iter().find_map(|(k, v)| {
            let path = if at.is_empty() {
                k.clone()
            } else {
                format!("{at}.{k}")
            };
            field_difference(v, y.get(k).unwrap_or(&Value::Null), path)
        }),
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .enumerate()
            .find_map(|(i, (v, w))| field_difference(v, w, format!("{at}[{i}]"))),
        _ if a == b => None,
        _ => Some((at, a.clone(), b.clone())),
    }
}

fn print_result(result: &Value, dir: &Path) {
    let node = result["node"].as_str().unwrap_or("?");
    for t in result["topics"].as_array().into_iter().flatten() {
        let verdict = if t["identical"] == true {
            "identical".to_string()
        } else {
            let d = &t["first_difference"];
            format!(
                "DIFFERENT from message {} (stamp {} ns): {} was {}, is {}",
                d["index"],
                d["stamp_ns"],
                d["field"].as_str().unwrap_or("?"),
                d["recorded"],
                d["resimulated"]
            )
        };
        println!(
            "{node} → {}: {} recorded, {} resimulated, {verdict}",
            t["topic"].as_str().unwrap_or("?"),
            t["recorded"],
            t["resimulated"]
        );
    }
    println!(
        "{}: the outputs of '{node}' are {} (comparison in {})",
        if result["identical"] == true {
            "ok"
        } else {
            "differ"
        },
        if result["identical"] == true {
            "byte-identical to the recording"
        } else {
            "not those recorded"
        },
        dir.join(RESULT_FILE).display()
    );
}

#[cfg(test)]
mod tests {
    use super::field_difference;
    use serde_json::json;

    #[test]
    fn the_first_differing_leaf_is_named_with_its_path() {
        let a = json!({"header": {"seq": 1}, "poses": [{"x": 1.0}, {"x": 2.0}]});
        let b = json!({"header": {"seq": 1}, "poses": [{"x": 1.0}, {"x": 2.5}]});
        let (path, was, now) = field_difference(&a, &b, String::new()).unwrap();
        assert_eq!(path, "poses[1].x");
        assert_eq!((was, now), (json!(2.0), json!(2.5)));
        assert!(field_difference(&a, &a, String::new()).is_none());
        let shorter = json!({"header": {"seq": 1}, "poses": [{"x": 1.0}]});
        assert_eq!(
            field_difference(&a, &shorter, String::new()).unwrap().0,
            "poses"
        );
    }
}
