//! Hostile input and faults against the real CLI (the reliability issue's cases): each is
//! bad input (exit 2, named, nothing started) or a clear run-time failure, and none hangs,
//! panics, leaks shared memory or leaves a process behind.

use caravan_tests::{
    PINGPONG, Scenario, alive, assert_refused, caravan, ping_pong, realtime_ping_pong, wait_until,
    workspace_bin, workspace_root,
};
use std::path::Path;
use std::process::{Command, Output, Stdio};

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).to_string()
}

#[test]
fn huge_or_tiny_durations_and_rates_are_bad_input_not_panics() {
    let s = Scenario::new("durations", PINGPONG);
    for (set, expected) in [
        ("group.duration=99999999999999999999h", "too long"),
        ("group.grace=2777777777777778h", "too long"),
        ("group.step_timeout=1e400s", "not a duration"),
        ("process.ping.rate=1e-30Hz", "out of range"),
        ("process.ping.rate=1e9Hz", "out of range"),
        ("process.ping.rate=2000Hz", "shorter than the group's tick"),
    ] {
        let out = s.run(&["--set", set]);
        assert_refused(&s, &out, &[set, expected]);
    }
    let out = s.run(&["--duration", "1e300h"]);
    assert_refused(&s, &out, &["not a duration"]);
    let out = caravan(&["topic", "hz", "demo/ping", "--seconds", "1e300"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("too long"), "{}", stderr(&out));
}

#[test]
fn a_bad_process_param_is_refused_before_anything_starts() {
    let s = Scenario::new(
        "param",
        &ping_pong().replace("params = { gain = 2.0 }", "params = { gain = \"high\" }"),
    );
    let out = s.run(&[]);
    // Named where it is written: the file, the process's params line, the key.
    let line = std::fs::read_to_string(&s.file)
        .unwrap()
        .lines()
        .position(|l| l.contains("gain = \"high\""))
        .unwrap()
        + 1;
    let at = format!("launch.toml:{line}");
    assert_refused(
        &s,
        &out,
        &[&at, "process 'pong'", "key 'gain'", "expected f64"],
    );
    // An unknown key, blamed on the override that set it.
    let s = Scenario::new("param-set", ping_pong());
    let out = s.run(&["--set", "process.pong.params.gian=1.0"]);
    assert_refused(&s, &out, &["--set process.pong.params.gian=1.0", "'gian'"]);
}

#[test]
fn a_missing_world_or_robot_file_is_refused_before_anything_starts() {
    let convoy = workspace_root().join("launch/convoy/convoy.toml");
    for (set, expected) in [
        (
            "process.physics.params.world=no-such-world.toml",
            "no-such-world.toml",
        ),
        (
            "process.physics.params.urdf=no-such-robot.urdf",
            "no-such-robot.urdf",
        ),
        ("process.physics.params.substeps=0", "key 'substeps'"),
    ] {
        // A scenario only for its unique group name, runs directory and checks.
        let s = Scenario::new("convoy-input", "");
        let out = Command::new(workspace_bin("caravan"))
            .arg("launch")
            .arg(&convoy)
            .args(["--quiet", "--set", set, "--set"])
            .arg(format!("group.name={}", s.group.name))
            .arg("--runs-dir")
            .arg(s.dir.join("runs"))
            .output()
            .unwrap();
        assert_refused(&s, &out, &["process 'physics'", expected]);
    }
}

#[test]
fn an_undeclared_host_is_bad_input() {
    let s = Scenario::new(
        "nohost",
        &ping_pong().replace("name = \"ping\"\n", "name = \"ping\"\nhost = \"nohost\"\n"),
    );
    let out = s.run(&[]);
    assert_refused(&s, &out, &["key 'host'", "'nohost' is not declared"]);
}

#[test]
fn a_lockstep_process_that_never_joins_fails_the_group_at_its_join_timeout() {
    let s = Scenario::new(
        "nojoin",
        &format!(
            "join_timeout = \"2s\"\n{}\n[[process]]\nname = \"sleeper\"\nexec = \"sleep 300\"\n",
            ping_pong()
        ),
    );
    let out = s.run(&[]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("sleeper") && err.contains("join_timeout"),
        "{err}"
    );
    assert_eq!(s.report()["run"]["outcome"], "failed");
    assert!(s.shm_entries().is_empty(), "{:?}", s.shm_entries());
}

#[test]
fn a_process_that_forks_leaves_no_orphan() {
    // One process exits at once, leaving a child in the background; another is stopped with
    // the group while its background child runs. Neither child may outlive the group.
    let s = Scenario::new("fork", "");
    let pids = s.dir.join("pids");
    std::fs::create_dir_all(&pids).unwrap();
    let body = format!(
        "clock = \"realtime\"\nduration = \"2s\"\n\n\
         [[process]]\nname = \"ping\"\nexec = \"caravan-demo ping\"\n\n\
         [[process]]\nname = \"leaver\"\nexec = \"sh\"\n\
         args = [\"-c\", \"sleep 300 & echo $! > {0}/leaver\"]\n\n\
         [[process]]\nname = \"waiter\"\nexec = \"sh\"\n\
         args = [\"-c\", \"sleep 300 & echo $! > {0}/waiter; wait\"]\n",
        pids.display()
    );
    std::fs::write(
        &s.file,
        format!("[group]\nname = \"{}\"\n{body}", s.group.name),
    )
    .unwrap();
    let out = s.run(&[]);
    assert!(out.status.success(), "{}", stderr(&out));
    for who in ["leaver", "waiter"] {
        let pid: i32 = std::fs::read_to_string(pids.join(who))
            .unwrap()
            .trim()
            .parse()
            .unwrap();
        wait_until(&format!("{who}'s background child {pid} is gone"), || {
            !alive(pid)
        });
    }
}

#[test]
fn two_launches_of_one_group_at_once_one_is_refused() {
    let s = Scenario::new("twice", &realtime_ping_pong("3s"));
    let start = || {
        s.command(&[])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (first, second) = (start(), start());
    let outs = [
        first.wait_with_output().unwrap(),
        second.wait_with_output().unwrap(),
    ];
    let codes: Vec<Option<i32>> = outs.iter().map(|o| o.status.code()).collect();
    let refused = outs
        .iter()
        .filter(|o| o.status.code() == Some(2))
        .collect::<Vec<_>>();
    assert_eq!(refused.len(), 1, "{codes:?}");
    assert!(
        stderr(refused[0]).contains("is already running"),
        "{}",
        stderr(refused[0])
    );
    assert!(codes.contains(&Some(0)), "{codes:?}");
    assert_eq!(s.run_dirs().len(), 1);
    assert!(s.shm_entries().is_empty(), "{:?}", s.shm_entries());
}

#[test]
fn inspecting_a_missing_group_fails_and_creates_nothing() {
    let s = Scenario::new("missing", "");
    let g = s.group.name.as_str();
    for args in [
        vec!["topic", "list", "--group", g],
        vec!["topic", "echo", "demo/ping", "-n", "1", "--group", g],
        vec!["topic", "hz", "demo/ping", "--seconds", "1", "--group", g],
        vec!["node", "list", "--group", g],
        vec!["record", "-o", "x.mcap", "--group", g],
    ] {
        let out = caravan(&args);
        assert_ne!(out.status.code(), Some(0), "{args:?}");
        assert!(
            stderr(&out).contains(&format!("no group '{g}' is running")),
            "{args:?}: {}",
            stderr(&out)
        );
        assert!(
            s.shm_entries().is_empty(),
            "{args:?}: {:?}",
            s.shm_entries()
        );
    }
    assert!(!Path::new("x.mcap").exists());
}

#[test]
fn no_file_of_a_running_group_is_open_to_other_users() {
    use std::os::unix::fs::PermissionsExt;
    let s = Scenario::new("private", &realtime_ping_pong("20s"));
    let child = s.command(&[]).spawn().unwrap();
    wait_until("both nodes run", || {
        let out = caravan(&["node", "list", "--group", &s.group.name]);
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        text.contains("ping") && text.contains("pong")
    });
    let open: Vec<String> = std::fs::read_dir("/dev/shm")
        .unwrap()
        .flatten()
        .filter(|e| {
            let name = e.file_name().to_string_lossy().to_string();
            name.starts_with(&caravan::group::prefix(&s.group.name))
                && e.metadata().unwrap().permissions().mode() & 0o077 != 0
        })
        .map(|e| e.file_name().to_string_lossy().to_string())
        .collect();
    // SAFETY: signalling our own child.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    assert!(child.wait_with_output().unwrap().status.success());
    assert!(open.is_empty(), "open to other users: {open:?}");
}

#[test]
fn a_trigger_nothing_publishes_is_a_warning_in_the_report() {
    let s = Scenario::new(
        "trigger",
        &ping_pong().replace("on = \"demo/ping\"", "on = \"demo/nobody\""),
    );
    let out = s.run(&[]);
    assert!(out.status.success(), "{}", stderr(&out));
    let report = s.report();
    let warnings = report["run"]["warnings"].as_array().unwrap();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    let w = warnings[0].as_str().unwrap();
    assert!(w.contains("'pong'") && w.contains("'demo/nobody'"), "{w}");
    assert!(stderr(&out).contains("warning:"), "{}", stderr(&out));
    let md = std::fs::read_to_string(s.run_dirs()[0].join("report.md")).unwrap();
    assert!(md.contains("**Warning:**"), "{md}");
}

#[test]
fn seeds_and_params_that_cannot_be_passed_on_are_bad_input() {
    let s = Scenario::new("seed", ping_pong());
    let out = s.run(&["--seed", "18446744073709551615"]);
    assert_refused(&s, &out, &["--seed", "18446744073709551615"]);
    let out = s.run(&["--seed", "-1"]);
    assert_refused(&s, &out, &["--seed", "-1"]);
    let out = s.run(&["--set", "group.seed=18446744073709551615"]);
    assert_refused(&s, &out, &["larger than 9223372036854775807"]);
    let big = "x".repeat(125_000); // under the 128 KiB an argument may take
    let out = s.run(&["--set", &format!("process.pong.params.note=\"{big}\"")]);
    assert_refused(
        &s,
        &out,
        &["process 'pong'", "key 'params'", "'note'", "name the file"],
    );
}

#[test]
fn chaos_kills_of_restartable_followers_are_survived_and_reported() {
    // The ground-truth convoy in lockstep; followers 3 and 4 may fail and restart, and a chaos
    // process SIGKILLs one of them at random steps, four times in all.
    let s = Scenario::new("chaos", "");
    let kills = s.dir.join("kills");
    let convoy = workspace_root().join("launch/convoy/convoy-truth.toml");
    let body = format!(
        "[[include]]\nfile = \"{convoy}\"\nset = [\"group.name={group}\", \"group.duration=40s\"]\n\n\
         [[process]]\nname = \"chaos\"\nexec = \"caravan-testnode chaos\"\nrate = \"10Hz\"\n\
         params = {{ count = 4, victims = [\"follower-3\", \"follower-4\"], out = \"{out}\" }}\n",
        convoy = convoy.display(),
        group = s.group.name,
        out = kills.display(),
    );
    std::fs::write(&s.file, body).unwrap();
    let policy = "restart=\"always\"";
    let mut sets = Vec::new();
    for f in ["follower-3", "follower-4"] {
        sets.push(format!("process.{f}.required=false"));
        sets.push(format!("process.{f}.{policy}"));
        sets.push(format!("process.{f}.max_restarts=10"));
        sets.push(format!("process.{f}.restart_backoff=\"50ms\""));
    }
    let args: Vec<&str> = sets.iter().flat_map(|s| ["--set", s.as_str()]).collect();
    let out = s.run(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let killed = std::fs::read_to_string(&kills).unwrap();
    let killed: Vec<&str> = killed.lines().collect();
    assert_eq!(killed.len(), 4, "{killed:?}");
    let report = s.report();
    assert_eq!(report["run"]["outcome"], "degraded");
    for f in ["follower-3", "follower-4"] {
        let times = killed
            .iter()
            .filter(|l| l.starts_with(&format!("{f} ")))
            .count();
        let node = report["nodes"]
            .as_array()
            .unwrap()
            .iter()
            .find(|n| n["name"] == f)
            .unwrap();
        assert_eq!(
            node["restarts"],
            times as u64,
            "{f}: {killed:?}\n{node}\n{}",
            stderr(&out)
        );
    }
    assert_eq!(report["run"]["sim_time_s"], 40.0);
    assert!(s.shm_entries().is_empty(), "{:?}", s.shm_entries());
    for line in &killed {
        let pid: i32 = line.split_whitespace().nth(1).unwrap().parse().unwrap();
        assert!(!alive(pid), "{line} still runs");
    }
}

#[test]
fn a_realtime_node_that_never_reports_fails_the_group_at_its_join_timeout() {
    let s = Scenario::new(
        "mute",
        "clock = \"realtime\"\nduration = \"30s\"\njoin_timeout = \"2s\"\n\n\
         [[process]]\nname = \"ping\"\nexec = \"caravan-demo ping\"\n\n\
         [[process]]\nname = \"mute\"\nexec = \"caravan-testnode mute\"\n",
    );
    let out = s.run(&[]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("'mute' has not reported a status"), "{err}");
    assert_eq!(s.report()["run"]["outcome"], "failed");
    assert!(s.shm_entries().is_empty(), "{:?}", s.shm_entries());
}

#[test]
fn a_stray_iceoryx2_config_in_the_working_directory_is_not_used() {
    // iceoryx2 reads config/iceoryx2.toml of the working directory as its fallback config;
    // one with another prefix must not take the launcher's or a node's dead-node clean-up
    // out of the group's namespace.
    let s = Scenario::new("stray", &realtime_ping_pong("10min"));
    let stray = format!("stray-{}_", std::process::id());
    let config = s.dir.join("config");
    std::fs::create_dir_all(&config).unwrap();
    caravan::group::write_config(&s.group.name, &config.join("iceoryx2.toml")).unwrap();
    let text = std::fs::read_to_string(config.join("iceoryx2.toml")).unwrap();
    let text = text.replace(&caravan::group::prefix(&s.group.name), &stray);
    std::fs::write(config.join("iceoryx2.toml"), text).unwrap();
    let child = s
        .command(&[])
        .current_dir(&s.dir)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut pong = None;
    wait_until("pong runs", || {
        let out = caravan(&["node", "list", "--group", &s.group.name]);
        pong = String::from_utf8_lossy(&out.stdout)
            .lines()
            .find(|l| l.starts_with("pong"))
            .and_then(|l| l.split_whitespace().last()?.parse::<i32>().ok());
        pong.is_some()
    });
    // A dead node: the launcher cleans up after it and stops the group (pong is required).
    // SAFETY: killing a process of the group under test.
    unsafe { libc::kill(pong.unwrap(), libc::SIGKILL) };
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        !stderr(&out).contains("No config file was loaded"),
        "{}",
        stderr(&out)
    );
    let strays: Vec<String> = std::fs::read_dir("/dev/shm")
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().to_string())
        .filter(|n| n.starts_with(&stray))
        .collect();
    assert!(strays.is_empty(), "{strays:?}");
    assert!(s.shm_entries().is_empty(), "{:?}", s.shm_entries());
}

/// Starts a realtime ping-pong group and kills its launcher with SIGKILL: its processes end
/// (parent-death signal) and its shared memory stays behind, stale.
fn stale_group(tag: &str) -> Scenario {
    let s = Scenario::new(tag, &realtime_ping_pong("10min"));
    let mut child = s.command(&[]).stderr(Stdio::piped()).spawn().unwrap();
    wait_until("ping and pong run", || {
        let out = caravan(&["node", "list", "--group", &s.group.name]);
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        text.contains("ping") && text.contains("pong")
    });
    child.kill().unwrap();
    child.wait().unwrap();
    wait_until("the group's processes are gone", || {
        !caravan(&["node", "list", "--group", &s.group.name])
            .status
            .success()
    });
    assert!(!s.shm_entries().is_empty());
    s
}

#[test]
fn clean_takes_the_group_named_and_needs_all_for_several() {
    let (a, b) = (stale_group("stale-a"), stale_group("stale-b"));
    // Which to clean is the user's choice: bad input until they make it.
    let out = caravan(&["clean"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains(&a.group.name) && err.contains(&b.group.name) && err.contains("--all"),
        "{err}"
    );
    assert!(!a.shm_entries().is_empty() && !b.shm_entries().is_empty());
    let out = caravan(&["clean", "--group", &a.group.name]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(a.shm_entries().is_empty(), "{:?}", a.shm_entries());
    assert!(
        !b.shm_entries().is_empty(),
        "the other group was cleaned too"
    );
    let out = caravan(&["clean", "--group", &b.group.name]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(b.shm_entries().is_empty(), "{:?}", b.shm_entries());
}
