//! The five-robot reference convoy, end to end in lockstep: physics, sensors, leader and
//! followers as real processes.

use caravan_tests::{TestGroup, workspace_bin};
use std::path::Path;
use std::process::Command;

/// Runs `launch/<file>` for 70 simulated seconds (the leader reaches D after about 47 s and
/// the followers line up behind it) and returns the report's convoy section.
fn run_convoy(file: &str) -> serde_json::Value {
    let group = TestGroup::new("convoy");
    let runs = std::env::temp_dir().join(format!("caravan-{}", group.name));
    let launch = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../launch")
        .join(file);
    let out = Command::new(workspace_bin("caravan"))
        .arg("launch")
        .arg(&launch)
        .args([
            "--quiet",
            "--duration",
            "70s",
            "--set",
            &format!("group.name={}", group.name),
        ])
        .arg("--runs-dir")
        .arg(&runs)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let run = std::fs::read_dir(&runs)
        .unwrap()
        .flatten()
        .next()
        .unwrap()
        .path();
    assert!(run.join("trajectories.svg").exists());
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("report.json")).unwrap()).unwrap();
    std::fs::remove_dir_all(runs).ok();
    report["convoy"].clone()
}

/// Every goal reached, gaps kept, no collision, order kept.
pub fn assert_convoy_succeeded(c: &serde_json::Value) {
    assert_eq!(c["robots"], 5, "{c}");
    assert_eq!(c["goals_total"], 4, "{c}");
    assert_eq!(c["goals_reached"], 4, "{c}");
    assert!(c["min_gap_m"].as_f64().unwrap() >= 0.15, "{c}");
    assert_eq!(c["collisions"], 0, "{c}");
    assert_eq!(c["order_kept"], true, "{c}");
    assert_eq!(c["followers"].as_array().unwrap().len(), 4);
}

#[test]
fn lockstep_convoy_reaches_every_goal_without_collision() {
    assert_convoy_succeeded(&run_convoy("convoy.toml"));
}

#[test]
fn custom_rust_follower_completes_the_convoy() {
    let c = run_convoy("convoy-custom.toml");
    assert_convoy_succeeded(&c);
    // The pure-pursuit follower (R2) stays on its predecessor's path.
    let r2 = &c["followers"][1];
    assert_eq!(r2["robot"], 2);
    assert!(
        r2["cross_track_to_predecessor_m"]["mean"].as_f64().unwrap() < 0.05,
        "{r2}"
    );
}
