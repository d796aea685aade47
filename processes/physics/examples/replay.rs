//! The physics process's work against rapier alone (docs/benchmarks.md, "Efficiency").
//!
//! Replays a lockstep run's recorded wheel set-points into the same `Simulation` the run's
//! physics process built, in a plain loop with no topics, and sets the CPU time it takes per
//! step beside the physics process's own, from the run's report:
//!
//!     cargo run --release -p caravan-physics --example replay -- RUN_DIR LAUNCH_DIR
//!
//! `RUN_DIR` is a run directory (its `launch.toml`, `record.mcap` and `report.json`; the run
//! must record `robot/*/wheel_setpoint`); `LAUNCH_DIR` the directory of the launch file it
//! ran, where the physics params' relative paths start. A set-point published at `t` is
//! applied at the first step after `t`, as the physics process sees it (a message is visible
//! one tick later). Prints one JSON line.

use caravan_physics::{Params, load};
use caravan_schemas::WheelSetpoint;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Set-points by time, ns, then robot.
type Setpoints = BTreeMap<u64, Vec<(usize, WheelSetpoint)>>;

fn main() {
    let args: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    let [run, launch_dir] = args.as_slice() else {
        eprintln!("usage: replay RUN_DIR LAUNCH_DIR");
        std::process::exit(2);
    };
    let (params, rate_hz) = physics_process(&run.join("launch.toml"));
    let period_ns = (1e9 / rate_hz).round() as u64;
    let params: Params = caravan::parse_params("physics", &params).expect("physics params");
    let dt_ns = period_ns / params.substeps.max(1) as u64;
    let mut sim = load(&params, launch_dir, dt_ns).expect("the run's world and robots");
    let setpoints = setpoints(&run.join("record.mcap"));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("report.json")).unwrap()).unwrap();
    let physics = report["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|n| n["name"] == "physics")
        .expect("a physics node in the report");
    let steps = physics["steps"].as_u64().unwrap();

    let mut pending = setpoints.iter().peekable();
    let started = caravan::thread_cpu_ns();
    for step in 0..steps {
        let now_ns = step * period_ns;
        while let Some((_, list)) = pending.next_if(|(t, _)| **t < now_ns) {
            for (robot, sp) in list {
                sim.set_setpoint(*robot, sp);
            }
        }
        sim.advance_to(now_ns, u64::MAX);
        std::hint::black_box(sim.take_collisions());
    }
    let replay_ms = (caravan::thread_cpu_ns() - started) as f64 / 1e6 / steps as f64;
    let in_step_ms = physics["compute_cpu_mean_ms"].as_f64().unwrap();
    let process_ms = physics["cpu_s"].as_f64().unwrap() * 1e3 / steps as f64;
    let line = serde_json::json!({
        "robots": sim.robot_count(),
        "steps": steps,
        "replay_ms_per_step": replay_ms,
        "process_in_step_ms_per_step": in_step_ms,
        "process_ms_per_step": process_ms,
        "in_step_over_replay": in_step_ms / replay_ms,
        "process_over_replay": process_ms / replay_ms,
    });
    println!("{line}");
}

/// The params and rate of the run's `caravan-physics` process.
fn physics_process(launch: &Path) -> (serde_json::Value, f64) {
    let text = std::fs::read_to_string(launch).expect("the run's launch.toml");
    let file: toml::Value = toml::from_str(&text).expect("a launch file");
    let process = file["process"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p.get("exec").and_then(|e| e.as_str()) == Some("caravan-physics"))
        .expect("a caravan-physics process");
    let rate = process
        .get("rate")
        .and_then(|r| r.as_str())
        .unwrap_or("100Hz");
    let hz = rate.trim_end_matches("Hz").parse().expect("a rate in Hz");
    let params = process.get("params").cloned();
    let params = serde_json::to_value(params.unwrap_or(toml::Value::Table(Default::default())));
    (params.unwrap(), hz)
}

/// Every recorded `robot/<i>/wheel_setpoint`, by its time.
fn setpoints(recording: &Path) -> Setpoints {
    let bytes = std::fs::read(recording).expect("the run's recording");
    let mut out = Setpoints::new();
    for message in mcap::MessageStream::new(&bytes).unwrap() {
        let message = message.unwrap();
        let topic = &message.channel.topic;
        let Some(robot) = topic
            .strip_prefix("robot/")
            .and_then(|rest| rest.strip_suffix("/wheel_setpoint"))
            .and_then(|i| i.parse().ok())
        else {
            continue;
        };
        let v: serde_json::Value = serde_json::from_slice(&message.data).unwrap();
        let sp = WheelSetpoint {
            left_rad_s: v["left_rad_s"].as_f64().unwrap(),
            right_rad_s: v["right_rad_s"].as_f64().unwrap(),
        };
        out.entry(message.log_time).or_default().push((robot, sp));
    }
    out
}
