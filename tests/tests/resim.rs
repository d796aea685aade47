//! Lockstep play (`caravan launch --play`) and deterministic re-simulation of one node
//! (`caravan resim`) against real recordings.

use caravan_tests::{PINGPONG, Scenario, caravan, run_convoy_with};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Output;

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).to_string()
}

/// `caravan resim FILE --node NODE …`, its run directories kept under `runs`.
fn resim(file: &Path, node: &str, runs: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "resim",
        file.to_str().unwrap(),
        "--node",
        node,
        "--quiet",
        "--json",
        "--runs-dir",
        runs.to_str().unwrap(),
    ];
    args.extend(extra);
    caravan(&args)
}

/// The comparison `resim --json` printed.
fn comparison(out: &Output) -> Value {
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "{e}: {}\n{}",
            String::from_utf8_lossy(&out.stdout),
            stderr(out)
        )
    })
}

/// Every topic of the comparison matched, and it held messages.
fn assert_identical(c: &Value, topics: &[&str]) {
    assert_eq!(c["identical"], true, "{c:#}");
    for topic in topics {
        let t = c["topics"]
            .as_array()
            .unwrap()
            .iter()
            .find(|t| t["topic"] == *topic)
            .unwrap_or_else(|| panic!("{topic} not compared: {c:#}"));
        assert!(t["recorded"].as_u64().unwrap() > 0, "{c:#}");
        assert_eq!(t["recorded"], t["resimulated"], "{c:#}");
    }
}

/// Runs `body` (a launch file after its group name) in lockstep for `duration` and returns
/// its scenario and recording.
fn recorded(tag: &str, body: &str, duration: &str) -> (Scenario, PathBuf) {
    let s = Scenario::new(tag, body);
    let out = s.run(&["--duration", duration]);
    assert!(out.status.success(), "{}", stderr(&out));
    let rec = s.run_dirs().pop().unwrap().join("record.mcap");
    (s, rec)
}

#[test]
fn pong_and_noise_resimulate_identically_and_a_change_shows_where_they_part() {
    let (s, rec) = recorded("resim-demo", PINGPONG, "5s");
    let runs = s.dir.join("resim");

    // pong is stepped by the played pings; noise by its period and the group's seed.
    for (node, topic) in [("pong", "demo/pong"), ("noise", "demo/noise")] {
        let out = resim(&rec, node, &runs, &[]);
        assert!(out.status.success(), "{node}: {}", stderr(&out));
        assert_identical(&comparison(&out), &[topic]);
    }

    // A changed gain changes pong's output (its echo of ping's count times the gain), and
    // resim says where: the first message echoing a count above 0.
    let out = resim(
        &rec,
        "pong",
        &runs,
        &["--set", "process.pong.params.gain=3.0"],
    );
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let c = comparison(&out);
    assert_eq!(c["identical"], false, "{c:#}");
    let difference = &c["topics"][0]["first_difference"];
    assert_eq!(difference["index"], 1, "{c:#}");
    assert_eq!(difference["field"], "x", "{c:#}");
    assert_eq!(
        difference["resimulated"].as_f64().unwrap(),
        1.5 * difference["recorded"].as_f64().unwrap(),
        "{c:#}"
    );
    // Another seed changes the noise.
    let out = resim(&rec, "noise", &runs, &["--set", "group.seed=4"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
}

#[test]
fn resim_refuses_what_it_cannot_compare() {
    // pong's output and the noise are recorded; pong's input, demo/ping, is not.
    let body = PINGPONG.replace(
        "record = [\"demo/*\"]",
        "record = [\"demo/pong\", \"demo/noise\"]",
    );
    assert_ne!(body, PINGPONG);
    let (s, rec) = recorded("resim-refused", &body, "2s");
    let runs = s.dir.join("resim");

    let out = resim(&rec, "pong", &runs, &[]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out)
            .contains("node 'pong' subscribes to demo/ping, which the recording does not hold"),
        "{}",
        stderr(&out)
    );
    for (node, extra, expected) in [
        // ping's output is not recorded.
        (
            "ping",
            vec![],
            "holds no message that node 'ping' published",
        ),
        (
            "nobody",
            vec![],
            "holds no message that node 'nobody' published",
        ),
        (
            "pong",
            vec!["--set", "group.clock=realtime"],
            "only lockstep runs can be re-simulated",
        ),
        (
            "pong",
            vec!["--set", "group.nonsense=1"],
            "the launch file attached to",
        ),
    ] {
        let out = resim(&rec, node, &runs, &extra);
        assert_eq!(out.status.code(), Some(2), "{node}: {}", stderr(&out));
        assert!(stderr(&out).contains(expected), "{node}: {}", stderr(&out));
    }
    for (file, expected) in [
        (
            Path::new("/dev/null"),
            "cannot read /dev/null: not a regular file",
        ),
        (&s.file, "not an MCAP file with a summary"),
    ] {
        let out = resim(file, "pong", &runs, &[]);
        assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
        assert!(stderr(&out).contains(expected), "{}", stderr(&out));
    }
    // Nothing was started for the refusals.
    let started = std::fs::read_dir(&runs).map_or(0, |d| d.count());
    assert_eq!(started, 1, "only the rerun of pong ran");
}

#[test]
fn launch_play_and_only_check_their_input() {
    let s = Scenario::new("play-bad", PINGPONG);
    let launch = s.file.to_str().unwrap();
    for (extra, expected) in [
        (
            vec!["--only", "pang"],
            "has no process 'pang'; did you mean",
        ),
        (
            vec!["--play", "/nonexistent.mcap"],
            "--play /nonexistent.mcap",
        ),
        (vec!["--play", launch], "is not an MCAP file"),
    ] {
        let out = s.run(&extra);
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {}", stderr(&out));
        assert!(
            stderr(&out).contains(expected),
            "{extra:?}: {}",
            stderr(&out)
        );
    }
    assert!(s.run_dirs().is_empty(), "nothing started");
    let out = caravan(&["launch", "x.toml", "--play-topics", "a"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
}

#[test]
fn slam_and_a_follower_resimulate_byte_identically_from_a_convoy_recording() {
    let run = run_convoy_with("convoy.toml", "12s", &[]);
    let rec = run.dir.join("record.mcap");
    let runs = run.dir.join("resim");
    let out = resim(&rec, "slam", &runs, &[]);
    assert!(out.status.success(), "{}", stderr(&out));
    let c = comparison(&out);
    assert_identical(&c, &["robot/0/pose", "map"]);
    // The rerun is judged by the comparison, not by the scenario's report plugin, which the
    // original run had.
    let plugins = |dir: &Path| {
        let facts: Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("run.json")).unwrap()).unwrap();
        facts["reports"].as_array().unwrap().len()
    };
    assert_eq!(plugins(&run.dir), 1);
    let rerun = Path::new(c["run_dir"].as_str().unwrap());
    assert_eq!(plugins(rerun), 0);
    assert!(rerun.join("resim.json").is_file());
    let out = resim(&rec, "follower-2", &runs, &[]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_identical(&comparison(&out), &["robot/2/wheel_setpoint"]);
}

#[test]
fn a_realtime_group_is_fed_a_recording_by_launch_play() {
    let (_source, rec) = recorded("play-rt-source", PINGPONG, "3s");
    // pong alone, in realtime: its pings come from the recording, at their recorded times.
    let s = Scenario::new("play-rt", PINGPONG);
    let out = s.run(&[
        "--clock",
        "realtime",
        "--duration",
        "4s",
        "--only",
        "pong",
        "--play",
        rec.to_str().unwrap(),
        "--play-topics",
        "demo/ping",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let report = s.report();
    let topic = |name: &str| {
        report["topics"]
            .as_array()
            .unwrap()
            .iter()
            .find(|t| t["name"] == name)
            .cloned()
            .unwrap_or_else(|| panic!("no {name} in {report:#}"))
    };
    // In realtime the recorder may join after the first message or two.
    let count = |name: &str| topic(name)["messages"].as_u64().unwrap();
    assert!((27..=31).contains(&count("demo/ping")), "{report:#}");
    assert!(count("demo/pong") + 4 >= count("demo/ping"), "{report:#}");
    let nodes: Vec<&str> = report["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|n| n["name"].as_str())
        .collect();
    assert!(!nodes.contains(&"ping"), "{nodes:?}");
}

/// A recording carries its types' descriptors: a type of a user's own (`beacon::Beacon`, which
/// Caravan's tree does not know) replays into a group where no process declares it, and is
/// recorded again message for message.
#[test]
fn a_recording_replays_a_type_that_no_process_of_the_group_knows() {
    let body = r#"clock = "lockstep"
record = ["beacon*", "demo/*"]

[[process]]
name = "beacon"
exec = "caravan-beacon"
rate = "10Hz"

[[process]]
name = "pong"
exec = "caravan-demo pong"
on = "demo/ping"
"#;
    let (s, rec) = recorded("replay-outside-type", body, "2s");
    let original = caravan_tests::recording::read(&rec);
    let broadcasts = caravan_tests::recording::messages(&original, "beacon");
    assert!(broadcasts.len() >= 19, "{} broadcasts", broadcasts.len());
    // pong alone: nothing in the group declares beacon::Beacon, the recording's player
    // publishes it from the descriptor the recording carries.
    let out = s.run(&[
        // Longer than the recording, so that its last message is played too.
        "--duration",
        "3s",
        "--only",
        "pong",
        "--play",
        rec.to_str().unwrap(),
        "--play-topics",
        "beacon",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let replayed = caravan_tests::recording::read(&s.run_dirs().pop().unwrap().join("record.mcap"));
    let text = |messages: Vec<Vec<u8>>| -> Vec<String> {
        messages
            .into_iter()
            .map(|m| String::from_utf8(m).unwrap())
            .collect()
    };
    let (broadcasts, again) = (
        text(broadcasts),
        text(caravan_tests::recording::messages(&replayed, "beacon")),
    );
    // The player makes the topic when its first message is due (so that a topic the group's
    // nodes make keeps their contract), and the recorder taps a topic from the advance after it
    // appears: the message at 0 s reaches the group but not the new recording.
    assert_eq!(
        again,
        broadcasts[1..],
        "the replayed broadcasts are the recorded ones"
    );
}
