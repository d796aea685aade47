//! The five-robot reference convoy, end to end in lockstep: physics, sensors, leader and
//! followers as real processes.

use caravan_tests::{TestGroup, workspace_bin};
use std::path::Path;
use std::process::Command;

#[test]
fn lockstep_convoy_reaches_every_goal_without_collision() {
    let group = TestGroup::new("convoy");
    let runs = std::env::temp_dir().join(format!("caravan-{}", group.name));
    let launch = Path::new(env!("CARGO_MANIFEST_DIR")).join("../launch/convoy.toml");
    let out = Command::new(workspace_bin("caravan"))
        .arg("launch")
        .arg(&launch)
        .args([
            "--quiet",
            // The leader reaches D after about 47 s and the followers line up behind it.
            "--duration",
            "70s",
            "--set",
            &format!("group.name={}", group.name),
            "--runs-dir",
        ])
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
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("report.json")).unwrap()).unwrap();
    let c = &report["convoy"];
    assert_eq!(c["robots"], 5, "{c}");
    assert_eq!(c["goals_total"], 4, "{c}");
    assert_eq!(c["goals_reached"], 4, "{c}");
    assert!(c["min_gap_m"].as_f64().unwrap() >= 0.15, "{c}");
    assert_eq!(c["collisions"], 0, "{c}");
    assert_eq!(c["order_kept"], true, "{c}");
    assert_eq!(c["followers"].as_array().unwrap().len(), 4);
    assert!(run.join("trajectories.svg").exists());
    std::fs::remove_dir_all(runs).ok();
}
