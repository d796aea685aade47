//! The reliability issue's second round: inputs of the same classes as its first list, tried
//! by an adversarial pass (absurd values that overflowed, special files, names past iceoryx2's
//! limits, escapes from the run directory, parents killed outright). Each is bad input (exit
//! 2, named, nothing started) or a clear failure, never a panic, a hang or an orphan.

use caravan_tests::{
    PINGPONG, Scenario, alive, assert_refused, caravan, children, launch_with_set,
    realtime_ping_pong, wait_until, workspace_bin, workspace_root,
};
use std::process::{Command, Stdio};

fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).to_string()
}

#[test]
fn absurd_process_params_that_overflowed_are_refused_before_the_start() {
    for (set, expected) in [
        ("process.physics.params.gravity=1e308", "'gravity'"),
        ("process.slam.params.slam.resolution=1e308", "resolution"),
        ("process.slam.params.save_map=../../escape", "'save_map'"),
        (
            "process.planner.params.global.search_margin=1e308",
            "search_margin",
        ),
        (
            "process.planner.params.local.v_samples=4000000000",
            "v_samples",
        ),
        (
            "process.physics.params.world=/dev/zero",
            "not a regular file",
        ),
    ] {
        let (code, err) = launch_with_set("convoy/convoy.toml", "1s", set);
        assert_eq!(code, 2, "{set}: {err}");
        assert!(!err.contains("panicked"), "{set}: {err}");
        assert!(
            err.contains(expected),
            "{set}: expected '{expected}' in {err}"
        );
    }
}

#[test]
fn an_emulated_cpu_slowdown_past_its_limit_is_refused() {
    let (code, err) = launch_with_set(
        "convoy/convoy-wlan.toml",
        "1s",
        "hosts.rpi-0.cpu_slowdown=1e13",
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("cpu_slowdown") && err.contains("1e6"), "{err}");
}

#[test]
fn a_process_name_longer_than_iceoryx2_takes_is_refused_at_its_line() {
    let long = "p".repeat(65);
    let s = Scenario::new(
        "longname",
        &PINGPONG.replace("name = \"noise\"", &format!("name = \"{long}\"")),
    );
    let out = s.run(&[]);
    assert_refused(&s, &out, &["key 'name'", "1 to 64"]);
}

#[test]
fn a_fifo_given_as_a_world_is_refused_at_once() {
    let s = Scenario::new("fifo", "");
    let fifo = s.dir.join("world.toml");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: mkfifo with a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let set = format!("process.physics.params.world={}", fifo.display());
    let (code, err) = launch_with_set("convoy/convoy.toml", "1s", &set);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("not a regular file"), "{err}");
}

#[test]
fn sweeps_of_more_seeds_than_a_sweep_takes_are_refused_at_once() {
    let pingpong = workspace_root().join("launch/pingpong.toml");
    let out = caravan(&[
        "sweep",
        pingpong.to_str().unwrap(),
        "--seeds",
        "0..9223372036854775807",
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("more than the 100000"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn inspection_arguments_that_mean_nothing_are_refused() {
    for args in [
        vec!["clean", "--group", "../../etc"],
        vec!["clean", "--group", ""],
        vec!["topic", "echo", "demo/ping", "-n", "0"],
        vec!["topic", "hz", "demo/ping", "--seconds", "0"],
        vec!["record", "", "-o", "x.mcap"],
    ] {
        let out = caravan(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(!stderr(&out).contains("panicked"), "{}", stderr(&out));
    }
}

#[test]
fn a_recording_that_cannot_be_written_fails_naming_it_without_a_panic() {
    let s = Scenario::new("full", &realtime_ping_pong("30s"));
    let mut group = s.command(&[]).stderr(Stdio::piped()).spawn().unwrap();
    wait_until("the group runs", || {
        caravan(&["topic", "list", "--group", &s.group.name])
            .stdout
            .windows(9)
            .any(|w| w == b"demo/ping")
    });
    // /dev/full answers every write with "No space left on device".
    let out = caravan(&[
        "record",
        "-o",
        "/dev/full",
        "--seconds",
        "2",
        "--group",
        &s.group.name,
    ]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("/dev/full"), "{}", stderr(&out));
    assert!(!stderr(&out).contains("panicked"), "{}", stderr(&out));
    // SAFETY: signalling our own child.
    unsafe { libc::kill(group.id() as i32, libc::SIGTERM) };
    assert!(group.wait().unwrap().success());
}

#[test]
fn a_launch_leaves_no_lock_or_config_in_the_temporary_directory() {
    let s = Scenario::new("tmpfiles", PINGPONG);
    let out = s.run(&["--duration", "1s"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let tmp = std::env::temp_dir();
    for suffix in ["lock", "iceoryx2.toml"] {
        let file = tmp.join(format!("caravan-group-{}.{suffix}", s.group.name));
        assert!(!file.exists(), "{} left behind", file.display());
    }
}

/// Waits until `parent` has started a child, kills `parent` with SIGKILL and waits until that
/// child (`what`) is gone too.
fn assert_child_dies_with(mut parent: std::process::Child, what: &str) {
    let mut child = 0;
    wait_until(&format!("{what} runs"), || {
        child = children(parent.id()).first().copied().unwrap_or(0);
        child != 0
    });
    parent.kill().unwrap(); // SIGKILL
    parent.wait().unwrap();
    wait_until(&format!("{what} {child} is gone"), || !alive(child));
}

#[test]
fn a_check_outlives_no_launcher_killed_outright() {
    // A program that does not understand CARAVAN_CHECK but is checked: its check blocks.
    let s = Scenario::new(
        "check-orphan",
        "clock = \"realtime\"\nduration = \"2s\"\n\n[[process]]\nname = \"sleeper\"\nexec = \"sleep\"\nargs = [\"300\"]\ncheck = true\n",
    );
    let launcher = s.command(&[]).stderr(Stdio::null()).spawn().unwrap();
    assert_child_dies_with(launcher, "the check");
}

#[test]
fn a_sweep_killed_outright_stops_its_launchers() {
    let s = Scenario::new("sweep-orphan", &realtime_ping_pong("60s"));
    let sweep = Command::new(workspace_bin("caravan"))
        .args([
            "sweep",
            s.file.to_str().unwrap(),
            "--seeds",
            "1",
            "--jobs",
            "1",
            "--out",
        ])
        .arg(s.dir.join("sweep"))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    assert_child_dies_with(sweep, "the sweep's launcher");
}

#[test]
fn a_trigger_that_is_not_one_topic_name_is_refused() {
    let s = Scenario::new("on-pattern", PINGPONG);
    for on in ["demo/*", "a//b", "/"] {
        let out = s.run(&["--set", &format!("process.pong.on={on}")]);
        assert_refused(&s, &out, &["key 'on'", "is not a topic name"]);
    }
}

#[test]
fn a_sweep_whose_output_is_a_file_is_refused_before_it_runs() {
    let s = Scenario::new("sweep-out", PINGPONG);
    let file = s.dir.join("taken.txt");
    std::fs::write(&file, "x").unwrap();
    let out = caravan(&[
        "sweep",
        s.file.to_str().unwrap(),
        "--seeds",
        "1",
        "--out",
        file.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("is not a directory"),
        "{}",
        stderr(&out)
    );
    assert!(s.run_dirs().is_empty());
}

#[test]
fn a_report_of_a_truncated_recording_names_the_file() {
    let s = Scenario::new("truncated", PINGPONG);
    assert!(s.run(&["--duration", "2s"]).status.success());
    let dir = s.run_dirs().pop().unwrap();
    let mcap = dir.join("record.mcap");
    let bytes = std::fs::read(&mcap).unwrap();
    std::fs::write(&mcap, &bytes[..bytes.len() / 2]).unwrap();
    let out = caravan(&["report", dir.to_str().unwrap()]);
    assert_ne!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(!stderr(&out).contains("panicked"), "{}", stderr(&out));
    assert!(
        stderr(&out).contains(mcap.to_str().unwrap()),
        "{}",
        stderr(&out)
    );
}

#[test]
fn a_sweep_over_the_keys_it_sets_itself_is_refused() {
    let pingpong = workspace_root().join("launch/pingpong.toml");
    for args in [["--grid", "group.name=a,b"], ["--set", "group.seed=4"]] {
        let mut all = vec!["sweep", pingpong.to_str().unwrap()];
        all.extend(args);
        let out = caravan(&all);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(
            stderr(&out).contains("sets group.name and group.seed itself"),
            "{}",
            stderr(&out)
        );
    }
}

/// Round 3: every command sends bad input to exit 2 and run-time failures to 1 (the table in
/// docs/launch.md). Before, the inspection commands, `info` and `play` exited 1 for all.
#[test]
fn inspection_commands_info_play_and_runs_dir_give_exit_2_for_bad_input() {
    let none = "no-such-group-for-exit-codes";
    for (args, expected) in [
        (
            vec!["topic", "pub", "demo/ping", "{}", "--group", none],
            "no group",
        ),
        (
            vec!["topic", "echo", "demo/ping", "--group", none],
            "no group",
        ),
        (
            vec!["topic", "hz", "demo/ping", "--group", none],
            "no group",
        ),
        (vec!["topic", "list", "--group", none], "no group"),
        (vec!["node", "list", "--group", none], "no group"),
        (vec!["node", "info", "pong", "--group", none], "no group"),
        (vec!["play", "/dev/null", "--group", none], "/dev/null"),
        (vec!["info", "/dev/null"], "/dev/null"),
        (
            vec!["info", "/no/such/recording.mcap"],
            "/no/such/recording.mcap",
        ),
    ] {
        let out = caravan(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(
            stderr(&out).contains(expected),
            "{args:?}: {}",
            stderr(&out)
        );
        assert!(
            !stderr(&out).contains("panicked"),
            "{args:?}: {}",
            stderr(&out)
        );
    }
    // --runs-dir naming a regular file: refused before anything starts.
    let s = Scenario::new("runs-file", PINGPONG);
    let file = s.dir.join("not-a-dir");
    std::fs::write(&file, "").unwrap();
    let out = caravan(&[
        "launch",
        s.file.to_str().unwrap(),
        "--runs-dir",
        file.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("not-a-dir"), "{}", stderr(&out));
    assert!(s.shm_entries().is_empty());
    // ... or a directory to be made under one.
    let under = file.join("runs");
    let out = caravan(&[
        "launch",
        s.file.to_str().unwrap(),
        "--runs-dir",
        under.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("not-a-dir is not a directory"),
        "{}",
        stderr(&out)
    );
    assert!(s.shm_entries().is_empty());
}

#[path = "hostile/round3.rs"]
mod round3;
