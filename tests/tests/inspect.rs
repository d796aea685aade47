//! The inspection commands (`topic`, `node`, `top`, `record`, `info`, `completions`) against
//! real running groups.

use caravan_tests::{PINGPONG, Scenario, caravan, wait_until};
use std::process::{Output, Stdio};

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).to_string()
}

fn json_of(out: &Output) -> serde_json::Value {
    assert!(out.status.success(), "{}", stderr(out));
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!("{e}: {}", String::from_utf8_lossy(&out.stdout));
    })
}

/// `caravan topic info <topic> --json` of group `g`, once the topic exists.
fn topic_info(g: &str, topic: &str) -> Option<serde_json::Value> {
    let out = caravan(&["topic", "info", topic, "--json", "--group", g]);
    serde_json::from_slice(&out.stdout).ok()
}

#[test]
fn topic_echo_without_a_count_exits_when_its_group_ends() {
    let s = Scenario::new("echo-end", PINGPONG);
    let group = s.start_realtime(4);
    // A node is listed once it runs, which can be before it has opened its topics.
    wait_until("ping publishes demo/ping", || {
        topic_info(&s.group.name, "demo/ping").is_some()
    });
    let echo = std::process::Command::new(caravan_tests::workspace_bin("caravan"))
        .args(["topic", "echo", "demo/ping", "--group", &s.group.name])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let pid = format!("pid {}", echo.id());
    wait_until("topic echo joins the group", || {
        let out = caravan(&["node", "list", "--group", &s.group.name]);
        String::from_utf8_lossy(&out.stdout).contains(&pid)
    });
    // SAFETY: signalling our own child.
    unsafe { libc::kill(group.id() as i32, libc::SIGTERM) };
    assert!(group.wait_with_output().unwrap().status.success());
    let mut echo = echo;
    wait_until("topic echo exits after its group ended", || {
        echo.try_wait().unwrap().is_some()
    });
    let out = echo.wait_with_output().unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("has ended"), "{}", stderr(&out));
}

#[test]
fn inspection_commands_see_a_running_group() {
    let s = Scenario::new("inspect", PINGPONG);
    let child = s.start_realtime(4);
    let g = s.group.name.as_str();
    let list =
        String::from_utf8_lossy(&caravan(&["topic", "list", "--group", g]).stdout).to_string();
    assert!(
        list.contains("demo/ping") && list.contains("caravan::Pose2D"),
        "{list}"
    );
    let json: serde_json::Value =
        serde_json::from_slice(&caravan(&["topic", "list", "--json", "--group", g]).stdout)
            .unwrap();
    let ping = json
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["name"] == "demo/ping");
    assert_eq!(ping.unwrap()["type"], "caravan::Pose2D", "{json}");
    let json: serde_json::Value =
        serde_json::from_slice(&caravan(&["node", "list", "--json", "--group", g]).stdout).unwrap();
    assert!(
        json.as_array().unwrap().iter().any(|n| n["name"] == "pong"),
        "{json}"
    );
    let echo = caravan(&["topic", "echo", "demo/pong", "-n", "3", "--group", g]);
    let lines: Vec<serde_json::Value> = String::from_utf8_lossy(&echo.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 3);
    assert!(
        lines
            .iter()
            .all(|l| l["x"].as_f64().unwrap() % 2.0 == 0.0 && l["header"]["source_id"].is_string())
    );
    let hz = String::from_utf8_lossy(
        &caravan(&["topic", "hz", "demo/ping", "--seconds", "2", "--group", g]).stdout,
    )
    .to_string();
    assert!(hz.contains("demo/ping:") && hz.contains("Hz"), "{hz}");
    let mcap = s.dir.join("manual.mcap");
    let rec = caravan(&[
        "record",
        "demo/sum",
        "-o",
        mcap.to_str().unwrap(),
        "--seconds",
        "2",
        "--group",
        g,
    ]);
    assert!(rec.status.success(), "{}", stderr(&rec));
    let bytes = std::fs::read(&mcap).unwrap();
    let topics: Vec<String> = mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| m.unwrap().channel.topic.clone())
        .collect();
    assert!(topics.iter().any(|t| t == "demo/sum"), "{topics:?}");
    assert!(
        topics.iter().all(|t| t.ends_with("demo/sum")),
        "the raw topic and its Foxglove view only: {topics:?}"
    );
    // `caravan info` reads it back from its summary.
    let info = caravan(&["info", "--json", mcap.to_str().unwrap()]);
    assert!(info.status.success(), "{}", stderr(&info));
    let info: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
    assert_eq!(info["indexed"], true);
    let sum = info["channels"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["topic"] == "demo/sum");
    assert_eq!(
        sum.unwrap()["messages"].as_u64(),
        Some(topics.iter().filter(|t| *t == "demo/sum").count() as u64)
    );
    assert!(
        info["metadata"]["run"]["wall_clock_start_ns"].is_string(),
        "{info}"
    );
    // 64 bytes of 0xFF inside the first chunk: the summary still reads, but `caravan info`
    // checks every chunk and refuses the file, naming it.
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
    let index = &summary.chunk_indexes[0];
    assert!(index.compressed_size > 200, "{index:?}");
    let chunk = index.chunk_start_offset as usize;
    let mut damaged = bytes.clone();
    damaged[chunk + 80..chunk + 144].fill(0xFF);
    let bad = mcap.with_extension("damaged.mcap");
    std::fs::write(&bad, &damaged).unwrap();
    let out = caravan(&["info", bad.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("damaged.mcap"), "{}", stderr(&out));
    let out = caravan(&["info", "no/such/file.mcap"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    // SAFETY: signalling our own child.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    assert!(child.wait_with_output().unwrap().status.success());
}

#[test]
fn topic_info_node_info_and_top_describe_a_running_group() {
    let s = Scenario::new("graph", PINGPONG);
    let child = s.start_realtime(4);
    let g = s.group.name.as_str();

    // demo/ping: ping publishes, pong subscribes (as does the launcher's recorder).
    let info = json_of(&caravan(&[
        "topic",
        "info",
        "demo/ping",
        "--json",
        "--group",
        g,
    ]));
    assert_eq!(info["type"], "caravan::Pose2D", "{info}");
    let names = |list: &serde_json::Value| -> Vec<String> {
        list.as_array()
            .unwrap()
            .iter()
            .map(|e| e["node"].as_str().unwrap().to_string())
            .collect()
    };
    assert_eq!(names(&info["publishers"]), ["ping"], "{info}");
    assert!(
        names(&info["subscribers"]).contains(&"pong".to_string()),
        "{info}"
    );
    let text = caravan(&["topic", "info", "demo/ping", "--group", g]);
    let text = String::from_utf8_lossy(&text.stdout).to_string();
    assert!(
        text.contains("Publishers: 1") && text.contains("ping (pid"),
        "{text}"
    );

    // pong subscribes to demo/ping, publishes demo/pong and its status.
    let pong = json_of(&caravan(&["node", "info", "pong", "--json", "--group", g]));
    let topics = |key: &str| -> Vec<String> {
        pong[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|t| t["name"].as_str().unwrap().to_string())
            .collect()
    };
    assert_eq!(topics("subscribes"), ["demo/ping"], "{pong}");
    assert_eq!(topics("publishes"), ["demo/pong", "status"], "{pong}");
    assert_eq!(pong["status"]["node"], "pong", "{pong}");
    assert!(pong["status"]["steps"].as_u64().unwrap() > 0, "{pong}");

    // top: one row per process, each stepping at its own rate.
    let top = json_of(&caravan(&["top", "--once", "--json", "--group", g]));
    let rows = top.as_array().unwrap();
    let mut nodes: Vec<&str> = rows.iter().map(|r| r["node"].as_str().unwrap()).collect();
    nodes.sort();
    assert_eq!(nodes, ["noise", "ping", "pong", "sum"], "{top}");
    for r in rows {
        assert!(r["pid"].as_i64().unwrap() > 0, "{r}");
        assert!(r["rss_kib"].as_u64().unwrap() > 0, "{r}");
    }
    let sum = rows.iter().find(|r| r["node"] == "sum").unwrap();
    let ping = rows.iter().find(|r| r["node"] == "ping").unwrap();
    // sum runs at 20 Hz and ping at 10 Hz: sum's rate is the higher whatever the load.
    assert!(
        sum["steps_per_s"].as_f64().unwrap() > ping["steps_per_s"].as_f64().unwrap(),
        "{top}"
    );

    // iceoryx2's own log lines go through Caravan's logging, at the level CARAVAN_LOG sets.
    let listed = |level: &str| {
        std::process::Command::new(caravan_tests::workspace_bin("caravan"))
            .args(["topic", "list", "--group", g])
            .env("CARAVAN_LOG", level)
            .output()
            .unwrap()
    };
    let traced = listed("trace");
    assert!(traced.status.success(), "{}", stderr(&traced));
    assert!(
        stderr(&traced).contains("caravan[caravan] TRACE iceoryx2: "),
        "{}",
        stderr(&traced)
    );
    assert_eq!(stderr(&listed("warn")), "");

    // Unknown names are errors that say what exists.
    let out = caravan(&["node", "info", "pnog", "--group", g]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        stderr(&out).contains("did you mean 'pong'?"),
        "{}",
        stderr(&out)
    );
    for command in ["info", "echo", "hz"] {
        let out = caravan(&["topic", command, "demo/pnig", "--group", g]);
        assert_eq!(out.status.code(), Some(2), "topic {command}: {out:?}");
        assert!(
            stderr(&out).contains("no topic 'demo/pnig'"),
            "topic {command}: {}",
            stderr(&out)
        );
    }

    // SAFETY: signalling our own child.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    assert!(child.wait_with_output().unwrap().status.success());
    assert!(s.shm_entries().is_empty());
}

#[test]
fn completions_are_printed_for_each_shell_and_an_unknown_shell_is_refused() {
    for shell in ["bash", "zsh", "fish"] {
        let out = caravan(&["completions", shell]);
        assert!(out.status.success(), "{shell}: {}", stderr(&out));
        let script = String::from_utf8_lossy(&out.stdout);
        for sub in ["launch", "topic", "top", "info"] {
            assert!(script.contains(sub), "{shell} completes {sub}");
        }
    }
    let out = caravan(&["completions", "tcsh"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("tcsh"), "{}", stderr(&out));
}

/// The `x` of every message on `topic` in the latest run's recording of `s`.
fn recorded_x(s: &Scenario, topic: &str) -> Vec<f64> {
    let run = s.run_dirs().pop().expect("a run directory");
    let bytes = caravan_tests::recording::read(&run.join("record.mcap"));
    caravan_tests::recording::messages(&bytes, topic)
        .iter()
        .map(|m| {
            serde_json::from_slice::<serde_json::Value>(m).unwrap()["x"]
                .as_f64()
                .unwrap()
        })
        .collect()
}

#[test]
fn play_and_topic_pub_publish_into_a_running_group() {
    // A recording of ping and pong in lockstep.
    let recorded = Scenario::new("play-source", PINGPONG);
    let out = recorded.run(&["--duration", "3s"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let pings = recorded_x(&recorded, "demo/ping");
    assert_eq!(pings.len(), 31);
    let mcap = recorded.run_dirs().pop().unwrap().join("record.mcap");

    // A group with pong alone: its pings come from the recording, then from topic pub.
    let body = format!("{}\n", caravan_tests::ping_pong()).replace(
        "[[process]]\nname = \"ping\"\nexec = \"caravan-demo ping\"\nrate = \"10Hz\"\n",
        "",
    );
    assert!(!body.contains("name = \"ping\""), "{body}");
    let s = Scenario::new("play", &body);
    let child = s.start_realtime(1);
    let g = s.group.name.as_str();
    // The recorder finds `demo/*` topics as they appear; pong's answers are recorded only
    // once it has subscribed to demo/pong.
    wait_until("the recorder subscribes to demo/pong", || {
        topic_info(g, "demo/pong")
            .is_some_and(|i| i["subscribers"].as_array().is_some_and(|s| !s.is_empty()))
    });
    let play = caravan(&[
        "play",
        mcap.to_str().unwrap(),
        "--topics",
        "demo/ping",
        "--speed",
        "4",
        "--group",
        g,
    ]);
    assert!(play.status.success(), "{}", stderr(&play));
    assert!(
        stderr(&play).contains("played 31 of 31 messages on 1 topics"),
        "{}",
        stderr(&play)
    );
    let publish = caravan(&[
        "topic",
        "pub",
        "demo/ping",
        r#"{"x": 1000, "y": 1}"#,
        "-n",
        "2",
        "--rate",
        "20",
        "--group",
        g,
    ]);
    assert!(publish.status.success(), "{}", stderr(&publish));

    // Bad input names what is wrong and publishes nothing.
    for (args, expected) in [
        (vec!["demo/ping", "{x: 1}"], "the message is not JSON"),
        (vec!["demo/ping", r#"{"z": 1}"#], "Pose2D has no field 'z'"),
        (
            vec!["demo/ping", r#"{"x": 1}"#, "--type", "caravan::Twist"],
            "carries caravan::Pose2D",
        ),
        (
            vec!["demo/nothing", r#"{"x": 1}"#],
            "give its type with --type",
        ),
    ] {
        let mut full = vec!["topic", "pub"];
        full.extend(args);
        full.extend(["--group", g]);
        let out = caravan(&full);
        assert_eq!(out.status.code(), Some(2), "{full:?}");
        assert!(
            stderr(&out).contains(expected),
            "{full:?}: {}",
            stderr(&out)
        );
    }
    let out = caravan(&["play", "/dev/null", "--group", g]);
    assert_eq!(out.status.code(), Some(2));
    let out = caravan(&[
        "play",
        mcap.to_str().unwrap(),
        "--topics",
        "nothing/*",
        "--group",
        g,
    ]);
    assert!(
        stderr(&out).contains("no recorded Caravan messages to play on nothing/*"),
        "{}",
        stderr(&out)
    );

    wait_until("pong answers every ping", || pong_steps(&s) >= 33);
    // SAFETY: signalling our own child.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    assert!(child.wait_with_output().unwrap().status.success());
    let mut expected: Vec<f64> = pings.iter().map(|x| 2.0 * x).collect();
    expected.extend([2000.0, 2000.0]);
    assert_eq!(recorded_x(&s, "demo/pong"), expected);
    assert!(s.shm_entries().is_empty());
}

/// Steps pong has made so far (one per ping it answered), from its status.
fn pong_steps(s: &Scenario) -> u64 {
    let out = caravan(&["node", "info", "pong", "--json", "--group", &s.group.name]);
    serde_json::from_slice::<serde_json::Value>(&out.stdout)
        .ok()
        .and_then(|v| v["status"]["steps"].as_u64())
        .unwrap_or(0)
}

/// A message type declared in a crate of its own (`examples/beacon`), which nothing in
/// Caravan's tree names: its publisher registers its descriptor with the group, and the
/// recorder, `topic echo` and `topic pub` read and write it through that.
#[test]
fn a_message_type_declared_outside_caravan_is_recorded_echoed_and_published_from_json() {
    let body = r#"clock = "realtime"
record = ["beacon*"]

[[process]]
name = "beacon"
exec = "caravan-beacon"
rate = "10Hz"
"#;
    let s = Scenario::new("outside-type", body);
    let child = s.start_realtime(1);
    let g = s.group.name.as_str();
    wait_until("the beacon broadcasts", || {
        topic_info(g, "beacon").is_some()
    });
    let info = topic_info(g, "beacon").unwrap();
    assert_eq!(info["type"], "beacon::Beacon", "{info}");

    let echo = json_of(&caravan(&[
        "topic", "echo", "beacon", "-n", "1", "--group", g,
    ]));
    assert_eq!(echo["label"], "unset", "{echo}");
    assert!(echo["id"].as_u64().unwrap() >= 1, "{echo}");
    assert!(echo["history"].as_array().unwrap().len() <= 4, "{echo}");
    assert!(echo.get("label_len").is_none() && echo.get("history_len").is_none());

    let set = r#"{"label": "from json", "position": {"x": 1.5, "y": -2.0, "z": 0.25}}"#;
    let publish = caravan(&["topic", "pub", "beacon/set", set, "-n", "3", "--group", g]);
    assert!(publish.status.success(), "{}", stderr(&publish));
    // A field the type lacks is named, with the type's own fields.
    let bad = caravan(&[
        "topic",
        "pub",
        "beacon/set",
        r#"{"colour": 1}"#,
        "--group",
        g,
    ]);
    assert!(
        stderr(&bad).contains("Beacon has no field 'colour'; its fields: id, strength_dbm"),
        "{}",
        stderr(&bad)
    );
    wait_until("the beacon says what it was told", || {
        let out = caravan(&["topic", "echo", "beacon", "-n", "1", "--group", g]);
        serde_json::from_slice::<serde_json::Value>(&out.stdout)
            .is_ok_and(|m| m["label"] == "from json")
    });
    // SAFETY: signalling our own child.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    assert!(child.wait_with_output().unwrap().status.success());

    let run = s.run_dirs().pop().expect("a run directory");
    let bytes = caravan_tests::recording::read(&run.join("record.mcap"));
    let told: Vec<serde_json::Value> = caravan_tests::recording::messages(&bytes, "beacon")
        .iter()
        .map(|m| serde_json::from_slice(m).unwrap())
        .filter(|m: &serde_json::Value| m["label"] == "from json")
        .collect();
    let last = told
        .last()
        .expect("recorded broadcasts with the label set from JSON");
    assert_eq!(last["position"]["x"], 1.5);
    assert_eq!(last["position"]["z"], 0.25);
    let history = last["history"].as_array().unwrap();
    assert_eq!(history.len(), 4);
    assert_eq!(
        history[3].as_f64().unwrap() as f32,
        last["strength_dbm"].as_f64().unwrap() as f32
    );
    assert!(s.shm_entries().is_empty(), "{:?}", s.shm_entries());
}

/// The same type in Python: an agent that has no class for it looks it up by name in the
/// group (`node.message_type`), receives broadcasts shown as `caravan topic echo` shows them,
/// and sets the beacon's label through `beacon/set` with the class it looked up.
#[test]
fn a_message_type_declared_outside_caravan_is_received_and_published_from_python() {
    let body = "clock = \"realtime\"\n\n[[process]]\nname = \"beacon\"\nexec = \"caravan-beacon\"\nrate = \"10Hz\"\n";
    let s = Scenario::new("outside-py", body);
    let child = s.start_realtime(1);
    let g = s.group.name.as_str();
    wait_until("the beacon broadcasts", || {
        topic_info(g, "beacon").is_some()
    });
    let echo = json_of(&caravan(&[
        "topic", "echo", "beacon", "-n", "1", "--group", g,
    ]));

    let root = caravan_tests::workspace_root();
    let told = r#"{"label": "from python", "position": {"x": 1.5, "y": -2.0, "z": 0.25}}"#;
    let out = std::process::Command::new(caravan_tests::python_env())
        .arg(root.join("tests/python/beacon_agent.py"))
        .arg(told)
        .env("PYTHONPATH", root.join("python"))
        .env("CARAVAN_GROUP", g)
        .env("CARAVAN_NODE", "py-beacon")
        .output()
        .unwrap();
    let said = format!("{}{}", String::from_utf8_lossy(&out.stdout), stderr(&out));
    assert!(out.status.success(), "{said}");
    let views: Vec<serde_json::Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let [first, answered] = views.as_slice() else {
        panic!("two broadcasts: {said}");
    };

    // Python's view has the shape `topic echo` prints: the same fields, nested alike, with the
    // label as text and the history cut to its length (echo adds the received header).
    let keys = |v: &serde_json::Value| -> Vec<String> {
        let keys = v.as_object().unwrap().keys().filter(|k| *k != "header");
        keys.cloned().collect()
    };
    assert_eq!(keys(first), keys(&echo), "{first}\n{echo}");
    assert_eq!(keys(&first["position"]), keys(&echo["position"]), "{first}");
    assert_eq!(first["label"], "unset", "{first}");
    assert_eq!(first["position"], echo["position"], "{first}\n{echo}");
    // Values as the beacon makes them: id counts broadcasts, strength falls 0.5 dBm a time,
    // the history keeps the last four strengths.
    let id = first["id"].as_u64().unwrap();
    let strength = first["strength_dbm"].as_f64().unwrap();
    assert!(id >= 1, "{first}");
    assert_eq!(strength as f32, -40.0 - id as f32 * 0.5, "{first}");
    let history = first["history"].as_array().unwrap();
    assert_eq!(history.len() as u64, id.min(4), "{first}");
    assert_eq!(
        history.last().unwrap().as_f64().unwrap() as f32,
        strength as f32
    );
    assert_eq!(
        echo["history"].as_array().unwrap().len() as u64,
        echo["id"].as_u64().unwrap().min(4)
    );

    // What Python published, the beacon took: Python saw it, and so does `topic echo`.
    assert_eq!(answered["position"]["x"], 1.5, "{answered}");
    assert_eq!(answered["position"]["y"], -2.0, "{answered}");
    assert_eq!(answered["position"]["z"], 0.25, "{answered}");
    let echo = json_of(&caravan(&[
        "topic", "echo", "beacon", "-n", "1", "--group", g,
    ]));
    assert_eq!(echo["label"], "from python", "{echo}");
    assert_eq!(echo["position"], answered["position"], "{echo}");

    // SAFETY: signalling our own child.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    assert!(child.wait_with_output().unwrap().status.success());
    assert!(s.shm_entries().is_empty(), "{:?}", s.shm_entries());
}

/// A type of a user's own crosses hosts though no process of the recording host declares it:
/// that host's bridge asks the publisher's for the descriptor and records the messages.
#[test]
fn a_message_type_declared_outside_caravan_is_recorded_on_another_host() {
    use caravan_tests::hosts::{Hosts, Launcher};
    let hosts = Hosts::new("ot", &["a", "b"]);
    let s = Scenario::new(
        "outside-type-hosts",
        &format!(
            r#"clock = "lockstep"
duration = "2s"
record = ["beacon"]

[[process]]
name = "pong"
exec = "caravan-demo pong"
on = "demo/ping"
host = "a"

[[process]]
name = "beacon"
exec = "caravan-beacon"
rate = "10Hz"
host = "b"

[hosts.a]
listen = ["{a}"]
clock = true

[hosts.b]
connect = ["{a}"]
"#,
            a = hosts.endpoint("a")
        ),
    );
    let launchers: Vec<(&str, Launcher)> = ["a", "b"]
        .into_iter()
        .map(|h| (h, Launcher::start(&hosts, h, &s)))
        .collect();
    for (host, launcher) in launchers {
        let (code, err) = launcher.finish();
        assert_eq!(code, Some(0), "host {host} ({:?}): {err}", hosts.how());
    }
    let run = hosts.run_dir("a", &s.dir);
    let bytes = caravan_tests::recording::read(&run.join("record.mcap"));
    let broadcasts = caravan_tests::recording::messages(&bytes, "beacon");
    assert!(broadcasts.len() >= 19, "{} broadcasts", broadcasts.len());
    let last: serde_json::Value = serde_json::from_slice(broadcasts.last().unwrap()).unwrap();
    assert_eq!(last["label"], "unset", "{last}");
    assert_eq!(last["history"].as_array().unwrap().len(), 4, "{last}");
}
