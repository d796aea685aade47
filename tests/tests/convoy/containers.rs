//! Containers (launch key `container`): nodes of one program in one process, stepped by one
//! thread in lockstep, each still a node of its own to the group.

use caravan_tests::recording::{all_messages, assert_same_messages, read};
use caravan_tests::{Scenario, assert_refused, node, run_convoy_with, workspace_root};

#[test]
fn a_convoy_in_containers_records_what_a_process_per_node_records() {
    let plain = run_convoy_with("convoy.toml", "5s", &[]);
    let contained = run_convoy_with("convoy-containers.toml", "5s", &[]);
    let messages =
        |run: &caravan_tests::ConvoyRun| all_messages(&read(&run.dir.join("record.mcap")));
    assert_same_messages(&messages(&plain), &messages(&contained));
    // Every node is still one to the report, with its own steps; its container is named.
    let (p, c) = (&plain.report, &contained.report);
    assert_eq!(c["nodes"].as_array().unwrap().len(), 18, "{c}");
    for (name, container) in [
        ("sensor-0", Some("sensors-localhost")),
        ("sensor-3", Some("sensors-localhost")),
        ("slam", Some("perception-localhost")),
        ("odometry-2", Some("perception-localhost")),
        ("follower-4", Some("agents-localhost")),
        ("physics", None),
        ("planner", None),
    ] {
        let n = node(c, name);
        assert_eq!(n["container"].as_str(), container, "{n}");
        assert_eq!(n["steps"], node(p, name)["steps"], "{n}");
        assert_eq!(n["exit_status"], "exited 0", "{n}");
    }
    // One process, and one log, per container.
    let logs = contained.dir.join("logs");
    assert!(logs.join("sensors-localhost.log").is_file());
    assert!(!logs.join("sensor-3.log").exists());
    let md = std::fs::read_to_string(contained.dir.join("report.md")).unwrap();
    assert!(md.contains("exited 0 (container agents-localhost)"), "{md}");
    // A batch of grants wakes a container once, a process per node once per step.
    let schedule = |r: &serde_json::Value| {
        let s = &r["run"]["schedule"];
        let count = |key: &str| s[key].as_u64().unwrap();
        (count("steps"), count("wake_ups"), count("batched_steps"))
    };
    let ((steps, plain_wakes, batched), (c_steps, c_wakes, c_batched)) = (schedule(p), schedule(c));
    // A process per node is woken once per grant: a grant of several periods is one.
    assert_eq!(
        (steps, plain_wakes, batched),
        (c_steps, steps - batched, c_batched),
        "{p}"
    );
    assert!(
        c_wakes * 10 < c_steps * 7,
        "{c_wakes} wake-ups for {c_steps} steps"
    );
    assert!(
        md.contains(&format!("{c_wakes} wake-ups sent with the grants")),
        "{md}"
    );
    // Every node runs on the scheduler's machine in Rust: each reports into its slot of the
    // shared page, and after its first report is granted there too. So every grant but each
    // node's first goes into a slot, and so does each node's stop at the end (and a grant
    // repeated after a slow step, if any): at least as many as the grants, one report each.
    for r in [p, c] {
        let s = &r["run"]["schedule"];
        let count = |key: &str| s[key].as_u64().unwrap();
        let grants = count("steps") - count("batched_steps");
        assert_eq!(count("slot_reports"), grants, "{s}");
        assert!(count("slot_grants") >= grants, "{s}");
    }
}

/// A lockstep group of two demo processes, `a` and `b`, with `extra` after `b`'s table.
fn pair(a_exec: &str, b_exec: &str, extra: &str) -> String {
    format!(
        "clock = \"lockstep\"\nduration = \"2s\"\n\n[[process]]\nname = \"a\"\nexec = \"{a_exec}\"\ncontainer = \"both\"\n\n\
         [[process]]\nname = \"b\"\nexec = \"{b_exec}\"\n{extra}"
    )
}

#[test]
fn members_of_one_container_with_different_programs_are_refused_naming_the_key() {
    let s = Scenario::new(
        "ctexec",
        &pair(
            "caravan-demo ping",
            "caravan-demo pong",
            "container = \"both\"\n",
        ),
    );
    let out = s.run(&[]);
    assert_refused(
        &s,
        &out,
        &[
            "key 'exec'",
            "launch.toml:13",
            "'a' and 'b' are in container 'both', one process, so their 'exec' must be the same",
        ],
    );
}

#[test]
fn members_on_different_hosts_are_refused_naming_the_container() {
    let body = pair(
        "caravan-demo noise",
        "caravan-demo noise",
        "container = \"both\"\nhost = \"pi\"\n\n[hosts.pi]\n",
    );
    let s = Scenario::new("cthost", &body);
    let out = s.run(&[]);
    assert_refused(&s, &out, &["key 'host'", "their 'host' must be the same"]);
}

#[test]
fn a_container_named_like_a_process_is_refused() {
    let s = Scenario::new(
        "ctname",
        &pair(
            "caravan-demo noise",
            "caravan-demo noise",
            "container = \"a\"\n",
        ),
    );
    let out = s.run(&[]);
    assert_refused(
        &s,
        &out,
        &["key 'container'", "'a' is the name of a process"],
    );
}

#[test]
fn a_python_agent_in_a_container_is_refused() {
    let python = workspace_root().join("python/caravan-python");
    let exec = format!("{} follower.py", python.display());
    let s = Scenario::new(
        "ctpy",
        &pair("caravan-demo noise", &exec, "container = \"c\"\n"),
    );
    let out = s.run(&[]);
    assert_refused(
        &s,
        &out,
        &[
            "key 'container'",
            "a Python agent runs a process of its own",
        ],
    );
}

/// A member that ends its process ends its container: every member is reported with the
/// container's exit, and the group fails as for any required process.
#[test]
fn a_member_that_exits_takes_its_container_with_it_and_fails_the_group() {
    let body = "clock = \"lockstep\"\nduration = \"20s\"\n\n\
        [[process]]\nname = \"ping\"\nexec = \"caravan-demo ping\"\n\n\
        [[process]]\nname = \"early\"\nexec = \"caravan-demo crash\"\ncontainer = \"crashers\"\nparams = { steps = 3 }\n\n\
        [[process]]\nname = \"late\"\nexec = \"caravan-demo crash\"\ncontainer = \"crashers\"\nparams = { steps = 1000 }\n";
    let s = Scenario::new("ctcrash", body);
    let out = s.run(&[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("required process 'crashers' exited 3"),
        "{err}"
    );
    let report = s.report();
    assert_eq!(report["run"]["outcome"], "failed");
    for name in ["early", "late"] {
        assert_eq!(node(&report, name)["exit_status"], "exited 3");
        assert_eq!(node(&report, name)["container"], "crashers");
    }
    assert_eq!(node(&report, "ping")["exit_status"], "exited 0");
    assert!(s.shm_entries().is_empty());
}

/// Containers step in lockstep; in realtime each member runs as a process of its own.
#[test]
fn in_realtime_a_containers_members_run_as_processes_of_their_own() {
    let body = pair(
        "caravan-demo noise",
        "caravan-demo noise",
        "container = \"both\"\n",
    )
    .replace("clock = \"lockstep\"", "clock = \"realtime\"");
    let s = Scenario::new("ctrt", &body);
    let out = s.run(&[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report = s.report();
    for name in ["a", "b"] {
        let n = node(&report, name);
        assert!(n["container"].is_null(), "{n}");
        assert!(n["steps"].as_u64().unwrap() > 0, "{n}");
    }
    let run = &s.run_dirs()[0];
    assert!(run.join("logs/a.log").is_file() && run.join("logs/b.log").is_file());
}
