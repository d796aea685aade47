//! `caravan-convoy-bench pipeline`: end-to-end latency of the leader's autonomy in realtime, from a
//! laser scan to the wheel set-point it caused, per hop and in total.
//!
//! The bench runs the convoy launch file with the real launcher in realtime mode and reads the
//! recording. The chain is scan → SLAM pose → planner command → leader set-point. Every node
//! in it works on the newest input it has, so an output was caused by the newest input sent
//! before it; an input counts once, for the first output that used it (its reaction time).
//! Each hop's latency is the time between the two messages' wall-clock send stamps (waiting
//! for the consumer's next step, delivery and compute), and the total runs from the scan's
//! send to the set-point's send. The simulated laser's own ray casting happens before the
//! scan is sent and is not part of the pipeline.

use anyhow::{Context, Result, bail};
use caravan_report::bench::{
    Machine, Percentiles, histogram, percentiles, run_dir_in, write_results,
};
use caravan_report::{RECORDING_FILE, RecordedMessage, read_all};
use caravan_schemas::topics;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::Duration;

#[derive(Args)]
pub struct PipelineArgs {
    /// A short run (10 s)
    #[arg(long)]
    pub quick: bool,
    /// Directory for pipeline.csv, pipeline.md and the run
    #[arg(long, default_value = "bench-results")]
    pub out: PathBuf,
    /// The convoy launch file
    #[arg(long, default_value = "launch/convoy/convoy.toml")]
    pub launch: PathBuf,
    /// Wall seconds to run [default: 60, or 10 with --quick]
    #[arg(long)]
    pub seconds: Option<u64>,
}

const LEADER: usize = 0;

/// One hop's (or the total's) latencies, ns.
struct Hop {
    name: String,
    latencies: Vec<u64>,
}

pub fn run(args: &PipelineArgs) -> Result<()> {
    let seconds = args.seconds.unwrap_or(if args.quick { 10 } else { 60 });
    let machine = Machine::detect();
    println!("caravan bench pipeline: {}", machine.describe());
    let runs = args.out.join("pipeline-runs");
    let _ = std::fs::remove_dir_all(&runs);
    std::fs::create_dir_all(&runs)?;
    let group = format!("bench-pipeline-{}", std::process::id());
    let bar = ProgressBar::new(seconds).with_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} s realtime convoy")
            .expect("valid template"),
    );
    let mut child = Command::new(super::caravan()?)
        .arg("launch")
        .arg(&args.launch)
        .args(["--clock", "realtime", "--quiet", "--duration"])
        .arg(format!("{seconds}s"))
        .arg("--set")
        .arg(format!("group.name={group}"))
        .arg("--runs-dir")
        .arg(&runs)
        .stdout(Stdio::null())
        .spawn()
        .context("cannot start caravan launch")?;
    let status = loop {
        if let Some(status) = child.try_wait()? {
            break status;
        }
        std::thread::sleep(Duration::from_millis(500));
        bar.set_position(bar.elapsed().as_secs().min(seconds));
    };
    bar.finish_and_clear();
    if !status.success() {
        bail!(
            "the realtime convoy failed ({status}); see {}",
            runs.display()
        );
    }
    let run_dir = run_dir_in(&runs)?;
    let messages = read_all(&run_dir.join(RECORDING_FILE))?;
    let hops = analyse(&messages);
    if hops.iter().any(|h| h.latencies.is_empty()) {
        bail!(
            "the recording in {} lacks a full scan → set-point chain; does the launch file record robot/0/scan, pose, cmd_vel and wheel_setpoint?",
            run_dir.display()
        );
    }
    write_results(
        &args.out,
        "pipeline",
        &machine,
        &table(&hops),
        &csv(&machine, &hops, seconds),
    )
}

/// Send times (wall ns) of a topic's messages, in order.
fn sends(messages: &[RecordedMessage], topic: &str) -> Vec<u64> {
    let mut out: Vec<u64> = messages
        .iter()
        .filter(|m| m.topic == topic)
        .filter_map(|m| m.header_u64("send_wall_ns"))
        .collect();
    out.sort_unstable();
    out
}

/// For each input, the first output that used it: the first output sent after it and before
/// the next input.
fn first_use(inputs: &[u64], outputs: &[u64]) -> Vec<Option<usize>> {
    let mut used = vec![None; inputs.len()];
    for (j, &out) in outputs.iter().enumerate() {
        let k = inputs.partition_point(|&t| t <= out);
        if k > 0 && used[k - 1].is_none() {
            used[k - 1] = Some(j);
        }
    }
    used
}

fn analyse(messages: &[RecordedMessage]) -> Vec<Hop> {
    let stages = [
        ("scan", topics::scan(LEADER).name().to_owned()),
        ("pose", topics::pose(LEADER).name().to_owned()),
        ("cmd_vel", topics::cmd_vel(LEADER).name().to_owned()),
        (
            "wheel_setpoint",
            topics::wheel_setpoint(LEADER).name().to_owned(),
        ),
    ];
    let times: Vec<Vec<u64>> = stages.iter().map(|(_, t)| sends(messages, t)).collect();
    let links: Vec<Vec<Option<usize>>> =
        times.windows(2).map(|w| first_use(&w[0], &w[1])).collect();
    let mut hops: Vec<Hop> = links
        .iter()
        .enumerate()
        .map(|(h, link)| Hop {
            name: format!("{} → {}", stages[h].0, stages[h + 1].0),
            latencies: link
                .iter()
                .enumerate()
                .filter_map(|(i, j)| j.map(|j| times[h + 1][j] - times[h][i]))
                .collect(),
        })
        .collect();
    let total = (0..times[0].len())
        .filter_map(|i| {
            let mut at = i;
            for link in &links {
                at = link[at]?;
            }
            Some(times[3][at] - times[0][i])
        })
        .collect();
    hops.push(Hop {
        name: "scan → wheel_setpoint (total)".into(),
        latencies: total,
    });
    hops
}

fn ms(ns: u64) -> f64 {
    ns as f64 / 1e6
}

fn table(hops: &[Hop]) -> String {
    let mut t = String::from(
        "| hop | samples | p50 ms | p90 ms | p99 ms | p99.9 ms | max ms |\n|---|---:|---:|---:|---:|---:|---:|\n",
    );
    for h in hops {
        let p = summary(h);
        let _ = writeln!(
            t,
            "| {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} |",
            h.name,
            h.latencies.len(),
            ms(p.p50_ns),
            ms(p.p90_ns),
            ms(p.p99_ns),
            ms(p.p999_ns),
            ms(p.max_ns)
        );
    }
    t
}

fn summary(h: &Hop) -> Percentiles {
    let mut hist = histogram();
    for &l in &h.latencies {
        hist.saturating_record(l.max(1));
    }
    percentiles(&hist)
}

fn csv(machine: &Machine, hops: &[Hop], seconds: u64) -> String {
    let mut out = format!(
        "# caravan bench pipeline (realtime convoy, {seconds} s)\n# cpu: {} ({} cores)\n# kernel: {}\nhop,samples,p50_ns,p90_ns,p99_ns,p999_ns,max_ns\n",
        machine.cpu, machine.cores, machine.kernel
    );
    for h in hops {
        let p = summary(h);
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{}",
            h.name,
            h.latencies.len(),
            p.p50_ns,
            p.p90_ns,
            p.p99_ns,
            p.p999_ns,
            p.max_ns
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::first_use;

    #[test]
    fn each_input_counts_once_for_the_first_output_after_it() {
        // Inputs at 10, 20, 30; outputs at 15, 17, 35. Input 20 was never used (no output
        // between 20 and 30).
        assert_eq!(
            first_use(&[10, 20, 30], &[15, 17, 35]),
            [Some(0), None, Some(2)]
        );
        assert_eq!(first_use(&[10], &[5]), [None]);
    }
}
