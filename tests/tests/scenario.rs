//! A tiny scenario added without touching the launcher: a demo group and its own report
//! plugin (`caravan-count-report`, in this crate), named in the launch file.

use caravan_tests::{Scenario, ping_pong, workspace_bin};
use serde_json::Value;
use std::process::Output;

/// The ping-pong demo group with a report plugin that counts `demo/ping`.
fn tiny(report_params: &str) -> String {
    format!(
        "{}\n[[report]]\nexec = \"caravan-count-report\"\nparams = {report_params}\n",
        ping_pong()
    )
}

/// Five simulated seconds of it.
const FIVE_SECONDS: [&str; 2] = ["--duration", "5s"];

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn read_json(path: &std::path::Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn a_scenario_report_plugin_adds_its_section() {
    // The plugin binary is built with the workspace's binaries.
    workspace_bin("caravan-count-report");
    let s = Scenario::new("tiny", &tiny(r#"{ topic = "demo/ping", field = "x" }"#));
    let out = s.run(&FIVE_SECONDS);
    assert!(out.status.success(), "{}", stderr(&out));
    let report = s.report();
    // ping steps at 0, 0.1, …, 5.0 s and publishes its step index as x.
    assert_eq!(report["count"]["messages"], 51);
    assert_eq!(report["count"]["sum"], (0..51).sum::<i32>() as f64);
    assert_eq!(report["count"]["topic"], "demo/ping");
    // The generic report is still there, and the recording agrees with the plugin.
    let ping = report["topics"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["name"] == "demo/ping")
        .unwrap();
    assert_eq!(ping["messages"], 51);
    let dir = s.run_dirs().pop().unwrap();
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(
        md.contains("## Count\n\n51 messages on `demo/ping`."),
        "{md}"
    );

    // `caravan report` reruns the plugin: same section after the files are gone.
    std::fs::remove_file(dir.join("report.json")).unwrap();
    std::fs::remove_dir_all(dir.join("sections")).unwrap();
    let again = std::process::Command::new(workspace_bin("caravan"))
        .arg("report")
        .arg(&dir)
        .output()
        .unwrap();
    assert!(again.status.success(), "{}", stderr(&again));
    assert_eq!(
        read_json(&dir.join("report.json"))["count"],
        report["count"]
    );
}

#[test]
fn bad_plugin_params_start_nothing() {
    workspace_bin("caravan-count-report");
    let s = Scenario::new("tiny-bad", &tiny(r#"{ topic = "demo/ping", feild = "x" }"#));
    let out = s.run(&FIVE_SECONDS);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains("caravan-count-report") && err.contains("'feild'"),
        "{err}"
    );
    // Named at the params' line of the file, as a process's bad param is.
    let written = std::fs::read_to_string(&s.file).unwrap();
    let line = 1 + written
        .lines()
        .position(|l| l.starts_with("params = { topic"))
        .unwrap();
    // Said once: not "caravan-count-report: params of report 'caravan-count-report': …".
    assert_eq!(err.matches("caravan-count-report").count(), 1, "{err}");
    assert!(
        err.contains(&format!(".toml:{line}:")),
        "line {line}: {err}"
    );
    assert!(s.run_dirs().is_empty(), "a run directory was created");
    assert!(s.shm_entries().is_empty());
}

#[test]
fn a_failing_plugin_fails_the_launch_but_keeps_the_report() {
    workspace_bin("caravan-count-report");
    let s = Scenario::new(
        "tiny-fail",
        &tiny(r#"{ topic = "demo/ping", fail = true }"#),
    );
    let out = s.run(&FIVE_SECONDS);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let report = s.report();
    assert_eq!(report["run"]["outcome"], "completed");
    assert!(report.get("count").is_none());
    let failed = &report["failed_sections"][0];
    assert_eq!(failed["exec"], "caravan-count-report");
    assert!(
        failed["message"]
            .as_str()
            .unwrap()
            .contains("asked to fail after reading 51 messages"),
        "{failed}"
    );
}

/// A plugin that never ends (as plotters did on an axis of 1e308) is killed at its entry's
/// `timeout`, and the run keeps its report, with the plugin named among the failed sections.
#[test]
fn a_plugin_that_never_ends_is_killed_at_its_time_limit() {
    let body = format!(
        "{}\n[[report]]\nexec = \"./stuck.sh\"\ntimeout = \"1s\"\n",
        ping_pong()
    );
    let s = Scenario::new("tiny-stuck", &body);
    let script = s.dir.join("stuck.sh");
    let pid_file = s.dir.join("stuck.pid");
    std::fs::write(
        &script,
        format!(
            "#!/bin/sh\n[ \"$1\" = --check ] && exit 0\necho $$ > '{}'\nexec sleep 600\n",
            pid_file.display()
        ),
    )
    .unwrap();
    std::fs::set_permissions(&script, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    // Not quiet: the last line says what the exit code says.
    let out = std::process::Command::new(caravan_tests::workspace_bin("caravan"))
        .args(["launch", s.file.to_str().unwrap(), "--runs-dir"])
        .arg(s.dir.join("runs"))
        .args(FIVE_SECONDS)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let said = stderr(&out);
    assert!(
        said.contains("completed, but a report plugin failed: simulated 5.0 s"),
        "{said}"
    );
    let report = s.report();
    assert_eq!(report["run"]["outcome"], "completed");
    let failed = &report["failed_sections"][0];
    assert_eq!(failed["exec"], "./stuck.sh");
    assert!(
        (failed["message"].as_str().unwrap())
            .contains("did not finish within its time limit of 1 s"),
        "{failed}"
    );
    let pid: i32 = std::fs::read_to_string(&pid_file)
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    caravan_tests::wait_until("the stuck plugin is gone", || !caravan_tests::alive(pid));
}

/// A plugin that ends but leaves a process running that holds its output open (`sleep 600 &`)
/// held the launcher until that process ended, past the plugin's time limit. What a plugin
/// leaves in its process group is killed when it ends.
#[test]
fn a_plugin_that_leaves_a_process_running_does_not_hold_the_launcher() {
    let body = format!("{}\n[[report]]\nexec = \"./leaves.sh\"\n", ping_pong());
    let s = Scenario::new("tiny-leaves", &body);
    let script = s.dir.join("leaves.sh");
    let pid_file = s.dir.join("left.pid");
    std::fs::write(
        &script,
        format!(
            "#!/bin/sh\n[ \"$1\" = --check ] && exit 0\nsleep 600 &\necho $! > '{}'\nexit 0\n",
            pid_file.display()
        ),
    )
    .unwrap();
    std::fs::set_permissions(&script, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    let mut launcher = s.command(&FIVE_SECONDS).spawn().unwrap();
    let mut status = None;
    caravan_tests::wait_until("the launcher ends", || {
        status = launcher.try_wait().unwrap();
        status.is_some()
    });
    assert_eq!(status.unwrap().code(), Some(0));
    let pid: i32 = std::fs::read_to_string(&pid_file)
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    caravan_tests::wait_until("what the plugin left is gone", || {
        !caravan_tests::alive(pid)
    });
}

/// A plugin that takes longer than a few seconds is said, so a launcher waiting for it does
/// not look hung; it is not killed before its time limit.
#[test]
fn a_slow_plugin_is_said_while_the_launcher_waits_for_it() {
    let body = format!(
        "{}\n[[report]]\nexec = \"./slow.sh\"\ntimeout = \"5m\"\n",
        ping_pong()
    );
    let s = Scenario::new("tiny-slow", &body);
    let script = s.dir.join("slow.sh");
    // Ends once the launcher has said it waits (its stderr is the file the test reads).
    let said = s.dir.join("launcher.err");
    std::fs::write(
        &script,
        format!(
            "#!/bin/sh\n[ \"$1\" = --check ] && exit 0\n\
             while ! grep -q 'waiting for report plugin' '{}'; do sleep 0.2; done\nexit 3\n",
            said.display()
        ),
    )
    .unwrap();
    std::fs::set_permissions(&script, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    let err = std::fs::File::create(&said).unwrap();
    let status = loud(&s).stderr(err).status().unwrap();
    let text = std::fs::read_to_string(&said).unwrap();
    assert!(
        text.contains("caravan: waiting for report plugin ./slow.sh (")
            && text.contains("s; its time limit is 300 s)"),
        "{text}"
    );
    // It ended on its own (exit 3), a failed plugin, not one killed at its limit.
    assert_eq!(status.code(), Some(1), "{text}");
    let failed = &s.report()["failed_sections"][0];
    assert!(
        !failed["message"].as_str().unwrap().contains("time limit"),
        "{failed}"
    );
}

/// `caravan launch` of `s` for five simulated seconds without `--quiet` (which
/// [`Scenario::command`] gives).
fn loud(s: &Scenario) -> std::process::Command {
    let mut cmd = std::process::Command::new(workspace_bin("caravan"));
    cmd.arg("launch")
        .arg(&s.file)
        .arg("--runs-dir")
        .arg(s.dir.join("runs"))
        .args(FIVE_SECONDS);
    cmd
}

/// `--quiet` holds for the launcher's wait for a slow plugin too: a plugin that runs past
/// the first "waiting for report plugin" (5 s) is not said.
#[test]
fn a_slow_plugin_is_not_said_under_quiet() {
    let body = format!(
        "{}\n[[report]]\nexec = \"./slow.sh\"\ntimeout = \"5m\"\n",
        ping_pong()
    );
    let s = Scenario::new("tiny-slow-quiet", &body);
    let script = s.dir.join("slow.sh");
    let slept = s.dir.join("slept");
    std::fs::write(
        &script,
        format!(
            "#!/bin/sh\n[ \"$1\" = --check ] && exit 0\nsleep 7\ntouch '{}'\nexit 3\n",
            slept.display()
        ),
    )
    .unwrap();
    std::fs::set_permissions(&script, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    let out = s.run(&FIVE_SECONDS);
    // The plugin ran its 7 s while the launcher waited for it.
    assert!(slept.exists(), "{}", stderr(&out));
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        !stderr(&out).contains("waiting for report plugin"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn a_report_time_limit_must_be_positive_and_bounded() {
    for (value, expected) in [("0s", "above 0"), ("25h", "at most 24 h"), ("soon", "soon")] {
        let body = format!(
            "{}\n[[report]]\nexec = \"caravan-count-report\"\ntimeout = \"{value}\"\n",
            ping_pong()
        );
        let s = Scenario::new("tiny-timeout", &body);
        let out = s.run(&FIVE_SECONDS);
        caravan_tests::assert_refused(&s, &out, &["timeout", expected]);
    }
}

#[test]
fn a_sweep_checks_report_plugin_params_before_starting() {
    workspace_bin("caravan-count-report");
    let s = Scenario::new("tiny-sweep", &tiny(r#"{ topic = "demo/ping" }"#));
    let out_dir = s.dir.join("sweep");
    let out = std::process::Command::new(workspace_bin("caravan"))
        .arg("sweep")
        .arg(&s.file)
        .args([
            "--grid",
            "report.0.params.topic=demo/ping,\"\"",
            "--quiet",
            "--out",
        ])
        .arg(&out_dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains("caravan-count-report") && err.contains("key 'topic'"),
        "{err}"
    );
    assert!(!out_dir.join("runs").exists(), "a run was started");
}
