//! `caravan-convoy-bench scale`: how the cost of a convoy grows with its size. One leader and N
//! followers (ground-truth poses, the reference follower law) in one physics process, run by
//! the real launcher in lockstep and in realtime, for each N. Per run: the real-time factor,
//! CPU time per simulated second (per process kind, and the launcher's own), the wake-up
//! jitter p99 of the nodes and the p99 delivery latency of the wheel set-points.
//!
//! Each run is a real `caravan launch` of a generated launch file in the output directory, so
//! the numbers include everything a user's run pays: processes, shared memory, the lockstep
//! scheduler and the recorder.

use anyhow::{Context, Result, bail};
use caravan_report::bench::{Machine, cpu_seconds, run_dir_in, write_results};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::Value;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The robot description shipped with the convoy, so the bench runs from any directory.
const ROBOT_URDF: &str = include_str!("../../../../launch/convoy/robots/convoy_bot.urdf");
/// Distance between neighbouring robots at the start, m.
const SPACING_M: f64 = 0.45;

#[derive(Args)]
pub struct ScaleArgs {
    /// A short run: N ∈ {1, 4}, 3 s each
    #[arg(long)]
    pub quick: bool,
    /// Directory for scale.csv, scale.md and the runs
    #[arg(long, default_value = "bench-results")]
    pub out: PathBuf,
    /// Follower counts, comma-separated [default: 1,4,16,64, or 1,4 with --quick]
    #[arg(long, value_delimiter = ',')]
    pub followers: Vec<usize>,
    /// Simulated (lockstep) or wall (realtime) seconds per run [default: 20, or 3 with --quick]
    #[arg(long)]
    pub seconds: Option<f64>,
    /// Clock modes, comma-separated [default: lockstep,realtime]
    #[arg(long, value_delimiter = ',', value_parser = ["lockstep", "realtime"])]
    pub clocks: Vec<String>,
    /// Run the leader's and the followers' agents in one container (launch key `container`;
    /// lockstep only: in realtime each still runs as a process of its own)
    #[arg(long)]
    pub containers: bool,
    /// The agents read every robot's pose from one message per physics step,
    /// `robots/state_true` (agent key `states_topic`), instead of each robot's `pose_true`
    #[arg(long)]
    pub team_states: bool,
}

/// One run's measurements.
struct Row {
    clock: String,
    followers: usize,
    processes: usize,
    sim_s: f64,
    wall_s: f64,
    rtf: f64,
    /// CPU seconds per simulated second.
    cpu_total: f64,
    cpu_physics: f64,
    cpu_agent_mean: f64,
    cpu_launcher: f64,
    jitter_p99_ms: f64,
    latency_p99_us: f64,
    deadline_misses: u64,
}

pub fn run(args: &ScaleArgs) -> Result<()> {
    let followers = match (&args.followers[..], args.quick) {
        ([], false) => vec![1, 4, 16, 64],
        ([], true) => vec![1, 4],
        (given, _) => given.to_vec(),
    };
    let seconds = args.seconds.unwrap_or(if args.quick { 3.0 } else { 20.0 });
    let clocks = if args.clocks.is_empty() {
        vec!["lockstep".to_string(), "realtime".to_string()]
    } else {
        args.clocks.clone()
    };
    let machine = Machine::detect();
    println!("caravan bench scale: {}", machine.describe());
    let runs_dir = args.out.join("scale-runs");
    std::fs::create_dir_all(&runs_dir)
        .with_context(|| format!("cannot create {}", runs_dir.display()))?;
    let bar = ProgressBar::new((followers.len() * clocks.len()) as u64).with_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} {msg}").expect("valid template"),
    );
    let mut rows = Vec::new();
    for clock in &clocks {
        for &n in &followers {
            bar.set_message(format!("{clock}, {n} followers"));
            rows.push(measure(&runs_dir, clock, n, seconds, args)?);
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    write_results(
        &args.out,
        "scale",
        &machine,
        &table(&rows),
        &csv(&machine, &rows, seconds),
    )
}

fn measure(
    runs_dir: &Path,
    clock: &str,
    followers: usize,
    seconds: f64,
    args: &ScaleArgs,
) -> Result<Row> {
    let name = format!("bench-scale-{clock}-{followers}-{}", std::process::id());
    let dir = runs_dir.join(&name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir)?;
    let file = write_scenario(&dir, &name, clock, followers, seconds, args)?;
    let before = children_cpu_s();
    let status = Command::new(super::caravan()?)
        .arg("launch")
        .arg(&file)
        .arg("--quiet")
        .arg("--runs-dir")
        .arg(dir.join("runs"))
        .stdout(Stdio::null())
        .status()
        .context("cannot start caravan launch")?;
    let cpu_all = children_cpu_s() - before;
    if !status.success() {
        bail!(
            "the {clock} run with {followers} followers failed ({status}); see {}",
            dir.join("runs").display()
        );
    }
    let run_dir = run_dir_in(&dir.join("runs"))?;
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(run_dir.join("report.json"))?)?;
    Ok(row(&report, clock, followers, cpu_all))
}

fn row(report: &Value, clock: &str, followers: usize, cpu_all: f64) -> Row {
    let run = &report["run"];
    let sim_s = run["sim_time_s"].as_f64().unwrap_or(0.0);
    let per_sim = |cpu: f64| if sim_s > 0.0 { cpu / sim_s } else { 0.0 };
    let nodes = report["nodes"].as_array().cloned().unwrap_or_default();
    // A container's members share its process's CPU time: count it once, split evenly.
    let members = |n: &Value| {
        let container = n["container"].as_str();
        let same = |m: &&Value| container.is_some() && m["container"].as_str() == container;
        nodes.iter().filter(same).count().max(1) as f64
    };
    let cpu = |n: &Value| n["cpu_s"].as_f64().unwrap_or(0.0) / members(n);
    let processes_cpu: f64 = nodes.iter().map(cpu).sum();
    let agents: Vec<f64> = nodes
        .iter()
        .filter(|n| {
            n["name"]
                .as_str()
                .is_some_and(|s| s.starts_with("follower-"))
        })
        .map(cpu)
        .collect();
    let max = |values: Vec<f64>| values.into_iter().fold(0.0, f64::max);
    Row {
        clock: clock.to_string(),
        followers,
        processes: nodes
            .iter()
            .map(|n| {
                n["container"]
                    .as_str()
                    .unwrap_or(n["name"].as_str().unwrap_or(""))
            })
            .collect::<std::collections::BTreeSet<_>>()
            .len(),
        sim_s,
        wall_s: run["wall_time_s"].as_f64().unwrap_or(0.0),
        rtf: run["real_time_factor"].as_f64().unwrap_or(0.0),
        cpu_total: per_sim(cpu_all),
        cpu_physics: per_sim(
            nodes
                .iter()
                .filter(|n| n["name"] == "physics")
                .map(cpu)
                .sum(),
        ),
        cpu_agent_mean: per_sim(agents.iter().sum::<f64>() / agents.len().max(1) as f64),
        cpu_launcher: per_sim((cpu_all - processes_cpu).max(0.0)),
        jitter_p99_ms: max(nodes
            .iter()
            .filter_map(|n| n["jitter_p99_ms"].as_f64())
            .collect()),
        latency_p99_us: max(report["topics"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|t| t["latency_us"]["p99"].as_f64())
            .collect()),
        deadline_misses: nodes
            .iter()
            .filter_map(|n| n["deadline_misses"].as_u64())
            .sum(),
    }
}

/// CPU seconds of this process's waited-for descendants so far (the launcher and, as it
/// reaps them, its processes).
fn children_cpu_s() -> f64 {
    // SAFETY: getrusage fills a plain-data struct.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut u) };
    cpu_seconds(&u)
}

/// Writes the world, the robot and the launch file of one run; returns the launch file.
fn write_scenario(
    dir: &Path,
    group: &str,
    clock: &str,
    followers: usize,
    seconds: f64,
    args: &ScaleArgs,
) -> Result<PathBuf> {
    let robots = followers + 1;
    let y = 1.5;
    let leader_x = 1.0 + SPACING_M * followers as f64;
    // Room for the whole line plus the leader's drive of at most 0.2 m/s.
    let length = leader_x + 0.2 * seconds + 3.0;
    std::fs::write(
        dir.join("world.toml"),
        format!(
            "[world]\nname = \"scale\"\nsize = [{length:.2}, 3.0]\n\n\
             [[wall]]\nfrom = [0.0, 0.0]\nto = [{length:.2}, 0.0]\n\n\
             [[wall]]\nfrom = [{length:.2}, 0.0]\nto = [{length:.2}, 3.0]\n\n\
             [[wall]]\nfrom = [{length:.2}, 3.0]\nto = [0.0, 3.0]\n\n\
             [[wall]]\nfrom = [0.0, 3.0]\nto = [0.0, 0.0]\n"
        ),
    )?;
    std::fs::write(dir.join("robot.urdf"), ROBOT_URDF)?;
    let poses: Vec<String> = (0..robots)
        .map(|i| format!("[{:.2}, {y}, 0.0]", leader_x - SPACING_M * i as f64))
        .collect();
    let goal_x = leader_x + 0.2 * seconds + 1.0;
    let container = if args.containers {
        "container = \"agents\"\n"
    } else {
        ""
    };
    let states = if args.team_states {
        ", states_topic = \"robots/state_true\""
    } else {
        ""
    };
    let mut text = format!(
        "# Generated by `caravan-convoy-bench scale`: a leader and {followers} followers.\n\n\
         [group]\nname = \"{group}\"\nclock = \"{clock}\"\nduration = \"{seconds}s\"\nseed = 1\n\
         record = [\"robot/*/wheel_setpoint\"]\n\n\
         [[process]]\nname = \"physics\"\nexec = \"caravan-physics\"\nrate = \"100Hz\"\n\
         params = {{ world = \"world.toml\", urdf = \"robot.urdf\", count = {robots}, poses = [{}] }}\n\n\
         [[process]]\nname = \"leader\"\nexec = \"caravan-convoy-agent\"\n\
         params = {{ robot = 0, urdf = \"robot.urdf\", mode = \"leader\", leader = {{ goals = [[{goal_x:.2}, {y}]] }}{states} }}\n{container}",
        poses.join(", ")
    );
    for i in 1..robots {
        let _ = write!(
            text,
            "\n[[process]]\nname = \"follower-{i}\"\nexec = \"caravan-convoy-agent\"\nparams = {{ robot = {i}, urdf = \"robot.urdf\"{states} }}\n{container}"
        );
    }
    let file = dir.join("launch.toml");
    std::fs::write(&file, text)?;
    Ok(file)
}

/// A row's values, formatted once for both the table and the CSV.
fn values(r: &Row) -> [String; 13] {
    [
        r.clock.clone(),
        r.followers.to_string(),
        r.processes.to_string(),
        format!("{:.2}", r.sim_s),
        format!("{:.2}", r.wall_s),
        format!("{:.2}", r.rtf),
        format!("{:.4}", r.cpu_total),
        format!("{:.4}", r.cpu_physics),
        format!("{:.5}", r.cpu_agent_mean),
        format!("{:.4}", r.cpu_launcher),
        format!("{:.2}", r.jitter_p99_ms),
        format!("{:.0}", r.latency_p99_us),
        r.deadline_misses.to_string(),
    ]
}

fn table(rows: &[Row]) -> String {
    let mut t = String::from(
        "| clock | followers | processes | sim s | wall s | real-time factor | CPU s per sim s: total | physics | follower agent (mean) | launcher | jitter p99 ms | set-point latency p99 µs | deadline misses |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in rows {
        let _ = writeln!(t, "| {} |", values(r).join(" | "));
    }
    t
}

fn csv(machine: &Machine, rows: &[Row], seconds: f64) -> String {
    let mut out = format!(
        "# caravan bench scale\n# cpu: {} ({} cores)\n# kernel: {}\n# seconds per run: {seconds}\n\
         clock,followers,processes,sim_s,wall_s,real_time_factor,cpu_per_sim_s,cpu_physics_per_sim_s,cpu_follower_agent_per_sim_s,cpu_launcher_per_sim_s,jitter_p99_ms,setpoint_latency_p99_us,deadline_misses\n",
        machine.cpu, machine.cores, machine.kernel
    );
    for r in rows {
        let _ = writeln!(out, "{}", values(r).join(","));
    }
    out
}
