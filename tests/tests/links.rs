//! Emulated network links between virtual hosts, with real processes in lockstep: a 10 Hz
//! source on host `a`, a sink on `a` (same host: zero-copy, one tick) and one on `b` (across
//! a link with 20 ms latency, 10 ms uniform jitter and 10 % loss).

use caravan_tests::Scenario;

const SECONDS: u64 = 60;

fn body(dir: &std::path::Path) -> String {
    format!(
        r#"clock = "lockstep"
duration = "{SECONDS}s"
seed = 5

[hosts.a]
[hosts.b]

[[links]]
between = ["a", "b"]
latency = "20ms"
jitter = "10ms"
loss = 0.1

[[process]]
name = "source"
exec = "caravan-testnode lockstep-source"
host = "a"
params = {{ topic = "t/x" }}

[[process]]
name = "near"
exec = "caravan-testnode lockstep-sink"
host = "a"
params = {{ topic = "t/x", out = "{near}" }}

[[process]]
name = "far"
exec = "caravan-testnode lockstep-sink"
host = "b"
params = {{ topic = "t/x", out = "{far}" }}
"#,
        near = dir.join("near.txt").display(),
        far = dir.join("far.txt").display(),
    )
}

/// (step time, message stamp) per message a sink received, ns.
fn receipts(path: &std::path::Path) -> Vec<(u64, u64)> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| {
            let (now, stamp) = l.split_once(' ').unwrap();
            (now.parse().unwrap(), stamp.parse().unwrap())
        })
        .collect()
}

#[test]
fn links_delay_and_drop_per_profile_and_same_host_stays_immediate() {
    let s = Scenario::new("links", "");
    std::fs::write(
        &s.file,
        format!("[group]\nname = \"{}\"\n{}", s.group.name, body(&s.dir)),
    )
    .unwrap();
    let out = s.run(&[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let sent = (SECONDS * 10 + 1) as f64; // 0 s … 60 s inclusive
    let tick = 1_000_000;

    // Same host: every message, exactly one tick after its stamp.
    let near = receipts(&s.dir.join("near.txt"));
    assert!(near.len() as f64 >= sent - 1.0, "{}", near.len());
    assert!(near.iter().all(|(now, stamp)| now - stamp == tick));

    // Across the link: nothing before its latency; the delay's mean and the loss match the
    // profile within sampling error (mean of U[0, 10 ms] has σ ≈ 0.13 ms over 540 messages,
    // the loss fraction σ ≈ 1.2 %).
    let far = receipts(&s.dir.join("far.txt"));
    let delays: Vec<f64> = far.iter().map(|(n, s)| (n - s) as f64 / 1e6).collect();
    assert!(
        delays.iter().all(|&d| d >= 21.0),
        "a message arrived early: {:?}",
        delays.iter().cloned().fold(f64::INFINITY, f64::min)
    );
    assert!(delays.iter().all(|&d| d <= 31.0 + 1e-6));
    let mean = delays.iter().sum::<f64>() / delays.len() as f64;
    assert!((mean - 26.0).abs() < 0.7, "mean delay {mean} ms");
    let lost = 1.0 - far.len() as f64 / sent;
    assert!((lost - 0.1).abs() < 0.05, "lost {lost}");

    // The report's links section counts the same.
    let report = s.report();
    let links = report["links"].as_array().expect("links section");
    assert_eq!(links.len(), 1, "{links:?}");
    let l = &links[0];
    assert_eq!(
        (l["from"].as_str(), l["to"].as_str()),
        (Some("a"), Some("b"))
    );
    let delivered = l["delivered"].as_u64().unwrap();
    assert!(delivered.abs_diff(far.len() as u64) <= 1, "{l}");
    assert!(
        (l["latency_ms"]["p50"].as_f64().unwrap() - 25.0).abs() < 1.5,
        "{l}"
    );

    // Lockstep stays deterministic with links on: a rerun delivers the same messages at the
    // same times.
    let again = s.run(&[]);
    assert!(again.status.success());
    assert_eq!(receipts(&s.dir.join("far.txt")), far);
}

/// The reference deployment over WLAN: the scan goes to the PC, SLAM's pose and the planner's
/// commands come back, follower poses go Pi to Pi; Pi nodes show their emulated compute time.
#[test]
fn convoy_over_wlan_reports_its_links_and_compute_budgets() {
    let run = caravan_tests::run_convoy_with("convoy-wlan.toml", "20s", &[]);
    let links = run.report["links"].as_array().expect("links section");
    let pairs: Vec<(&str, &str)> = links
        .iter()
        .map(|l| (l["from"].as_str().unwrap(), l["to"].as_str().unwrap()))
        .collect();
    for pair in [
        ("rpi-0", "pc"),
        ("pc", "rpi-0"),
        ("pc", "rpi-1"),
        ("rpi-1", "rpi-2"),
        ("rpi-3", "rpi-4"),
    ] {
        assert!(pairs.contains(&pair), "{pair:?} missing from {pairs:?}");
    }
    for l in links {
        assert!(l["delivered"].as_u64().unwrap() > 0, "{l}");
        // 1 % loss: well under 5 % over hundreds of messages.
        assert!(l["loss_pct"].as_f64().unwrap() < 5.0, "{l}");
        assert!(l["latency_ms"]["p50"].as_f64().unwrap() >= 2.0, "{l}");
    }
    let nodes = run.report["nodes"].as_array().unwrap();
    let node = |name: &str| nodes.iter().find(|n| n["name"] == name).unwrap();
    let f = node("follower-2");
    assert_eq!(f["host"], "rpi-2");
    let emulated = f["emulated_compute_mean_ms"].as_f64().unwrap();
    let measured = f["compute_cpu_mean_ms"].as_f64().unwrap();
    assert!(measured > 0.0, "{f}");
    assert!((emulated - 12.0 * measured).abs() < 1e-9, "{f}");
    assert!(node("slam")["emulated_compute_mean_ms"].is_null());
}

/// The convoy's nodes on the reference hosts over a bad WLAN (50 ms + U[0, 8 ms], 5 % loss,
/// 1 % spikes), without CPU budgets so that the run is reproducible (links are seeded).
const BAD_WLAN: &str = r#"
[[include]]
file = "CONVOY"
args = { world_host = "world", pc_host = "pc", leader_host = "rpi-0", robot_host = "rpi-{i}" }

[hosts.world]
[hosts.pc]
[hosts.rpi-0]
[hosts.rpi-1]
[hosts.rpi-2]
[hosts.rpi-3]
[hosts.rpi-4]

[[links]]
between = ["rpi-*", "pc"]
LINK
[[links]]
between = ["rpi-*", "rpi-*"]
LINK
"#;

/// The bad WLAN's latency, jitter, loss and spikes (no bandwidth limit), for every link of
/// `BAD_WLAN`.
const BAD_LINK: &str = r#"latency = "50ms"
jitter = "8ms"
loss = 0.05
spike_probability = 0.01
spike = ["50ms", "100ms"]"#;

/// Followers keep the 0.15 m safety distance over a bad WLAN, through the stops after the
/// leader's goals. With a fixed stop margin (before the speed-aware rule) this run came within
/// 0.129 m.
#[test]
fn convoy_keeps_its_safety_distance_over_a_bad_wlan() {
    let convoy = caravan_tests::workspace_root().join("launch/convoy/convoy.toml");
    let s = Scenario::new(
        "badwlan",
        &BAD_WLAN
            .replace("CONVOY", &convoy.to_string_lossy())
            .replace("LINK", BAD_LINK),
    );
    let out = s.run(&["--duration", "60s", "--seed", "3"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report = s.report();
    let c = &report["convoy"];
    assert!(c["goals_reached"].as_u64().unwrap() >= 3, "{c}");
    assert!(c["min_gap_m"].as_f64().unwrap() >= 0.15, "{c}");
    let link = report["links"]
        .as_array()
        .unwrap()
        .iter()
        .find(|l| l["from"] == "rpi-3" && l["to"] == "rpi-4")
        .expect("the rpi-3 → rpi-4 link");
    assert!(
        link["latency_ms"]["p50"].as_f64().unwrap() >= 50.0,
        "{link}"
    );
}

/// A host with a CPU budget publishes later in simulated time by its CPU time × the
/// slowdown; a subscriber stepped by messages still sees each message, exactly when it shows.
#[test]
fn cpu_budgets_delay_outputs_by_emulated_compute_time() {
    let s = Scenario::new("budget", "");
    let sink = s.dir.join("sink.txt");
    std::fs::write(
        &s.file,
        format!(
            r#"[group]
name = "{}"
clock = "lockstep"
duration = "10s"

[hosts.slow]
cpu_slowdown = 100.0
[hosts.fast]

[[process]]
name = "source"
exec = "caravan-testnode lockstep-source"
host = "slow"
params = {{ topic = "t/x" }}

[[process]]
name = "sink"
exec = "caravan-testnode lockstep-sink"
host = "fast"
params = {{ topic = "t/x", out = "{}" }}
"#,
            s.group.name,
            sink.display()
        ),
    )
    .unwrap();
    let out = s.run(&[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let got = receipts(&sink);
    assert!(got.len() >= 100, "{}", got.len());
    let tick = 1_000_000;
    for (now, stamp) in &got {
        // The source steps every 100 ms; its messages are stamped at least a tick later (its
        // CPU time × 100, rounded up to the tick; well under 100 ms for a step of
        // microseconds, even on a loaded machine, as waiting for a core is not counted), and
        // seen exactly one tick after that.
        assert!(stamp % 100_000_000 >= tick, "stamp {stamp}");
        assert_eq!(now - stamp, tick);
    }
    let report = s.report();
    let source = report["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|n| n["name"] == "source")
        .unwrap()
        .clone();
    let emulated = source["emulated_compute_mean_ms"].as_f64().unwrap();
    let measured = source["compute_cpu_mean_ms"].as_f64().unwrap();
    assert!(measured > 0.0, "{source}");
    assert!((emulated - 100.0 * measured).abs() < 1e-6, "{source}");
}
