//! One group on three hosts (`caravan launch FILE --host NAME` per host), topics crossing
//! between them over zenoh. The hosts are namespaces of this machine (see
//! `caravan_tests::hosts`).

use caravan_tests::hosts::{Hosts, Launcher, free_port, pid_of, shm_left};
use caravan_tests::{PINGPONG, Scenario, caravan, recording, wait_until};

/// The report's entry for the real network from `from` to `to`, in run directory `run`.
fn network_link(run: &std::path::Path, from: &str, to: &str) -> serde_json::Value {
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(run.join("report.json")).unwrap()).unwrap();
    let links = report["links"].as_array().cloned().unwrap_or_default();
    links
        .into_iter()
        .find(|l| l["kind"] == "network" && l["from"] == from && l["to"] == to)
        .unwrap_or_else(|| panic!("no network link {from} → {to}: {report:#}"))
}

fn hosts_table(hosts: &Hosts, c_required: bool) -> String {
    format!(
        r#"
[hosts.a]
listen = ["{a}"]

[hosts.b]
listen = ["{b}"]
connect = ["{a}"]

[hosts.c]
connect = ["{a}"]
required = {c_required}
"#,
        a = hosts.endpoint("a"),
        b = hosts.endpoint("b"),
    )
}

#[test]
fn a_lossless_topic_crosses_hosts_whole_and_in_order() {
    let hosts = Hosts::new("ll", &["a", "b", "c"]);
    let count = 2000;
    let s = Scenario::new(
        "hosts-lossless",
        &format!(
            r#"clock = "realtime"
duration = "5min"
{}
[[process]]
name = "source"
exec = "caravan-testnode stream"
host = "a"
rate = "400Hz"
params = {{ topic = "bulk", count = {count}, value = 7.0, readers = 2 }}

[[process]]
name = "sink-b"
exec = "caravan-testnode subscribe"
host = "b"
params = {{ topic = "bulk", count = {count}, value = 7.0 }}

[[process]]
name = "sink-c"
exec = "caravan-testnode subscribe"
host = "c"
params = {{ topic = "bulk", count = {count}, value = 7.0 }}
"#,
            hosts_table(&hosts, true)
        ),
    );
    let launchers: Vec<(&str, Launcher)> = ["a", "b", "c"]
        .into_iter()
        .map(|h| (h, Launcher::start(&hosts, h, &s)))
        .collect();
    for (host, launcher) in launchers {
        let (code, err) = launcher.finish();
        assert_eq!(code, Some(0), "host {host} ({:?}): {err}", hosts.how());
        assert!(err.contains("completed"), "host {host}: {err}");
        assert_eq!(shm_left(&s, host), "", "host {host} left shared memory");
        let run = hosts.run_dir(host, &s.dir);
        if host != "a" {
            let log = std::fs::read_to_string(run.join(format!("logs/sink-{host}.log")))
                .unwrap_or_default();
            assert!(
                log.contains(&format!("received {count} missed 0")),
                "host {host}: {log}"
            );
            // The report measures the real network the messages crossed.
            let network = network_link(&run, "a", host);
            assert_eq!(network["delivered"], count, "host {host}: {network}");
            assert!(network["latency_ms"]["p50"].as_f64().is_some(), "{network}");
        }
    }
}

#[test]
fn a_lockstep_group_across_hosts_records_the_bytes_of_one_host() {
    let hosts = Hosts::new("ls", &["a", "b", "c"]);
    // ping on a, pong and noise on b, sum on c: every message a node reads comes from another
    // host, and a records them all.
    let body = PINGPONG
        .replace("rate = \"10Hz\"", "rate = \"10Hz\"\nhost = \"a\"")
        .replace("on = \"demo/ping\"", "on = \"demo/ping\"\nhost = \"b\"")
        .replace("rate = \"20Hz\"", "rate = \"20Hz\"\nhost = \"c\"")
        .replace("rate = \"7Hz\"", "rate = \"7Hz\"\nhost = \"b\"");
    let s = Scenario::new(
        "hosts-lockstep",
        &format!(
            "{body}\n[hosts.a]\nlisten = [\"{a}\"]\nclock = true\n\n[hosts.b]\nconnect = [\"{a}\"]\n\n[hosts.c]\nconnect = [\"{a}\"]\n",
            a = hosts.endpoint("a"),
        ),
    );
    // The same file on one machine first, with the arguments a's launcher gets but --host
    // (the recording says which command made it).
    let runs = s.dir.join("runs-a");
    let file = s.file.to_str().unwrap();
    let out = caravan(&[
        "launch",
        file,
        "--quiet",
        "--runs-dir",
        runs.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let one_dir = hosts.run_dir("a", &s.dir);
    let one = std::fs::read(one_dir.join("record.mcap")).unwrap();
    std::fs::remove_dir_all(one_dir).unwrap();
    assert!(recording::channels(&one).contains_key("demo/sum"));
    let launchers: Vec<(&str, Launcher)> = ["a", "b", "c"]
        .into_iter()
        .map(|h| (h, Launcher::start(&hosts, h, &s)))
        .collect();
    let ended: Vec<_> = launchers
        .into_iter()
        .map(|(host, l)| (host, l.finish()))
        .collect();
    for (host, (code, _)) in &ended {
        assert_eq!(
            *code,
            Some(0),
            "host {host} ({:?}): {ended:#?}",
            hosts.how()
        );
        assert_eq!(shm_left(&s, host), "", "host {host} left shared memory");
    }
    // b and c ran their processes; a kept the time and recorded.
    for host in ["b", "c"] {
        let run = hosts.run_dir(host, &s.dir);
        let report: serde_json::Value =
            serde_json::from_slice(&std::fs::read(run.join("report.json")).unwrap()).unwrap();
        assert_eq!(report["run"]["clock_host"], "a", "{report:#}");
    }
    let run_a = hosts.run_dir("a", &s.dir);
    let many = std::fs::read(run_a.join("record.mcap")).unwrap();
    // Every message crossed into a: pong and noise from b, sum from c.
    for (from, messages) in [("b", 100 + 70), ("c", 201)] {
        let link = network_link(&run_a, from, "a");
        assert!(link["delivered"].as_u64().unwrap() >= messages, "{link}");
    }
    assert!(
        one == many,
        "the recording across hosts differs from the one on one host ({:?}): {:?} vs {:?}",
        hosts.how(),
        recording::channels(&one),
        recording::channels(&many)
    );
}

#[test]
fn a_process_hung_on_another_host_fails_a_lockstep_group() {
    let hosts = Hosts::new("hang", &["a", "b"]);
    let s = Scenario::new(
        "hosts-hang",
        &format!(
            r#"clock = "lockstep"
duration = "1min"
step_timeout = "2s"

{hosts}
[[process]]
name = "ping"
exec = "caravan-demo ping"
host = "a"

[[process]]
name = "stuck"
exec = "caravan-testnode hang"
host = "b"
params = {{ count = 3 }}
"#,
            hosts = pair(hosts.endpoint("a"))
        ),
    );
    let a = Launcher::start(&hosts, "a", &s);
    let b = Launcher::start(&hosts, "b", &s);
    let (code, err) = a.finish();
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("process 'stuck' has not finished a step") && err.contains("on host 'b'"),
        "{err}"
    );
    let (code, err) = b.finish();
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("host 'a' stopped the group (failed"), "{err}");
    for host in ["a", "b"] {
        assert_eq!(shm_left(&s, host), "", "host {host} left shared memory");
    }
}

/// Hosts a (listening) and b over TLS (QUIC), b with certificate `b_cert` (a file of
/// `tests/data/tls`), and a lossless stream from a to b. The join wait is long enough for
/// b's dials to reach a's handshake on a loaded machine: a dial made before a listens is
/// retried after a growing pause, and under 5 s one run's b never got as far as the
/// handshake (it said only that a did not join).
fn tls_group(hosts: &Hosts, b_cert: &str) -> Scenario {
    let tls = concat!(env!("CARGO_MANIFEST_DIR"), "/data/tls");
    let a = hosts.endpoint("a").replace("tcp/", "quic/");
    Scenario::new(
        "hosts-tls",
        &format!(
            r#"clock = "realtime"
duration = "5min"
join_timeout = "15s"

[hosts.a]
listen = ["{a}"]
tls = {{ ca = "{tls}/ca.pem", certificate = "{tls}/host.pem", key = "{tls}/host.key" }}

[hosts.b]
connect = ["{a}"]
tls = {{ ca = "{tls}/ca.pem", certificate = "{tls}/{b_cert}.pem", key = "{tls}/{b_cert}.key" }}

[[process]]
name = "source"
exec = "caravan-testnode stream"
host = "a"
rate = "200Hz"
params = {{ topic = "bulk", count = 200, value = 7.0, readers = 1 }}

[[process]]
name = "sink"
exec = "caravan-testnode subscribe"
host = "b"
params = {{ topic = "bulk", count = 200, value = 7.0 }}
"#
        ),
    )
}

#[test]
fn hosts_join_over_tls_only_with_the_groups_certificates() {
    let hosts = Hosts::new("tls", &["a", "b"]);
    let s = tls_group(&hosts, "host");
    let (a, b) = (
        Launcher::start(&hosts, "a", &s),
        Launcher::start(&hosts, "b", &s),
    );
    // Both hosts' output on failure: one host's reason is often in the other's.
    let ended = [("a", a.finish()), ("b", b.finish())];
    for (host, (code, _)) in &ended {
        assert_eq!(
            *code,
            Some(0),
            "host {host} ({:?}): {ended:#?}",
            hosts.how()
        );
    }
    let log = std::fs::read_to_string(hosts.run_dir("b", &s.dir).join("logs/sink.log")).unwrap();
    assert!(log.contains("received 200 missed 0"), "{log}");
    // A certificate of another authority does not get b in: a waits for it, then gives up.
    // (Fresh hosts: a's port of the first group may still be taken.)
    let hosts = Hosts::new("tls2", &["a", "b"]);
    let s = tls_group(&hosts, "outsider");
    let (a, b) = (
        Launcher::start(&hosts, "a", &s),
        Launcher::start(&hosts, "b", &s),
    );
    // Each side names the other: a refused b's certificate, b's handshake with a failed.
    let (code, err) = a.finish();
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("'b' did not join"), "{err}");
    assert!(
        err.contains("refused the certificate of a peer (host 'b', the only one not joined)"),
        "{err}"
    );
    assert!(err.contains("not signed by the group's authority"), "{err}");
    let (code, err) = b.finish();
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("TLS handshake with host 'a'"), "{err}");
}

#[test]
fn a_host_that_leaves_is_reported_and_stops_the_group_if_required() {
    let hosts = Hosts::new("kill", &["a", "b", "c"]);
    let s = Scenario::new(
        "hosts-kill",
        &idle_group(&hosts_table(&hosts, false), &["a", "b", "c"]),
    );
    let a = Launcher::start(&hosts, "a", &s);
    let b = Launcher::start(&hosts, "b", &s);
    let c = Launcher::start(&hosts, "c", &s);
    wait_until("every host runs its part", || {
        [&a, &b, &c]
            .iter()
            .all(|l| l.stderr().contains("run directory"))
    });
    // c is not required: the others go on without it.
    unsafe { libc::kill(pid_of(&s, "c"), libc::SIGKILL) };
    c.finish();
    for l in [&a, &b] {
        wait_until("the others report c's leaving", || {
            l.stderr()
                .contains("host 'c' left the group; going on without it")
        });
    }
    // b is: a stops, and says why.
    unsafe { libc::kill(pid_of(&s, "b"), libc::SIGKILL) };
    b.finish();
    let (code, err) = a.finish();
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("host 'b' left the group before its processes finished"),
        "{err}"
    );
    assert!(err.contains("failed"), "{err}");
    assert_eq!(shm_left(&s, "a"), "", "host a left shared memory");
}

#[test]
fn a_second_launcher_of_a_host_gives_way_and_the_group_goes_on() {
    let hosts = Hosts::new("twin", &["a", "b"]);
    let s = Scenario::new(
        "hosts-twin",
        &idle_group(&pair(hosts.endpoint("a")), &["a", "b"]),
    );
    let a = Launcher::start(&hosts, "a", &s);
    let b = Launcher::start(&hosts, "b", &s);
    wait_until("both hosts run their part", || {
        [&a, &b]
            .iter()
            .all(|l| l.stderr().contains("run directory"))
    });
    let a_pid = pid_of(&s, "a");
    // The same host started again (a mistake), as if on another machine (on this one, its
    // launcher would find the group running): it gives way as soon as it sees the first.
    let twin = Launcher::start_in(&hosts, "b", &s, &s.dir.join("twin"));
    let (code, err) = twin.finish();
    assert_eq!(code, Some(1), "({:?}) {err}", hosts.how());
    assert!(
        err.contains("another launcher already runs host 'b' of this group"),
        "{err}"
    );
    wait_until("the first launcher of b notices", || {
        b.stderr().contains("a second launcher for host 'b' joined")
    });
    // The group went on: b did not leave, and a stops it for both.
    unsafe { libc::kill(a_pid, libc::SIGINT) };
    let (_, err_b) = b.finish();
    let (_, err_a) = a.finish();
    assert!(
        err_b.contains("host 'a' stopped the group (interrupted"),
        "{err_b}"
    );
    assert!(!err_a.contains("left the group"), "{err_a}");
    assert!(!err_b.contains("failed"), "{err_b}");
}

/// A realtime group that runs until it is stopped: an idle process on each host of `names`,
/// under the `[hosts]` tables `hosts_toml`.
fn idle_group(hosts_toml: &str, names: &[&str]) -> String {
    let mut file = format!("clock = \"realtime\"\nduration = \"10min\"\n{hosts_toml}\n");
    for n in names {
        file += &format!(
            "[[process]]\nname = \"idle-{n}\"\nexec = \"caravan-testnode idle\"\nhost = \"{n}\"\n\n"
        );
    }
    file
}

/// Two hosts on loopback ports, `a` listening.
fn two_hosts(clock: &str, extra: &str) -> String {
    let port = free_port();
    format!(
        r#"clock = "{clock}"
duration = "1min"
{extra}
{}
[[process]]
name = "idle"
exec = "caravan-testnode idle"
host = "a"
"#,
        pair(&format!("tcp/127.0.0.1:{port}"))
    )
}

/// Hosts a, listening at `endpoint`, and b, dialling it.
fn pair(endpoint: &str) -> String {
    format!("[hosts.a]\nlisten = [\"{endpoint}\"]\n\n[hosts.b]\nconnect = [\"{endpoint}\"]\n")
}

#[test]
fn a_group_whose_required_host_never_joins_does_not_start() {
    let s = Scenario::new(
        "hosts-alone",
        &two_hosts("realtime", "join_timeout = \"1s\""),
    );
    let out = s.run(&["--host", "a"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("host(s) 'b' did not join within 1s"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(s.run_dirs().is_empty(), "a run directory was made: {err}");
    assert!(s.shm_entries().is_empty(), "{:?}", s.shm_entries());
}

/// Host a publishes `mix` as `WheelSetpoint` (after `publisher_ms`), host b reads it as
/// `Pose2D` (after `reader_ms`): the group fails on every host, saying why.
fn mismatch(publisher_ms: u64, reader_ms: u64, expected: &[&str]) {
    let hosts = Hosts::new("mix", &["a", "b"]);
    let s = Scenario::new(
        "hosts-mix",
        &format!(
            r#"clock = "realtime"
duration = "5min"

{}
[[process]]
name = "writer"
exec = "caravan-testnode wrong-type"
host = "a"
params = {{ topic = "mix", count = {publisher_ms} }}

[[process]]
name = "reader"
exec = "caravan-testnode subscribe"
host = "b"
params = {{ topic = "mix", count = 10, value = 0.0, delay_ms = {reader_ms} }}
"#,
            pair(hosts.endpoint("a")),
        ),
    );
    let a = Launcher::start(&hosts, "a", &s);
    let b = Launcher::start(&hosts, "b", &s);
    let (code_a, err_a) = a.finish();
    let (code_b, err_b) = b.finish();
    let both = format!("host a:\n{err_a}\nhost b:\n{err_b}");
    assert_eq!((code_a, code_b), (Some(1), Some(1)), "{both}");
    for e in expected {
        assert!(both.contains(e), "expected '{e}' in:\n{both}");
    }
    assert!(!both.contains("panicked"), "{both}");
}

#[test]
fn a_topic_read_and_published_as_different_types_on_two_hosts_fails_the_group() {
    // The reader first: the writer meets the topic as made for the reader, as on one host.
    mismatch(
        3000,
        0,
        &[
            "'mix'",
            "cannot open as caravan::WheelSetpoint",
            "different message type",
        ],
    );
    // The writer first: the writer's host cannot send the topic as the reader reads it.
    mismatch(
        0,
        3000,
        &[
            "topic 'mix': host 'b' reads it as caravan::Pose2D",
            "host 'a' stopped the group (failed",
        ],
    );
}

#[path = "hosts/cleanup.rs"]
mod cleanup;
#[path = "hosts/join.rs"]
mod join;
#[path = "hosts/keys.rs"]
mod keys;
#[path = "hosts/pause.rs"]
mod pause;
#[path = "hosts/refusals.rs"]
mod refusals;
