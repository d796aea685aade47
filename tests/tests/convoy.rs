//! The five-robot reference convoy, end to end in lockstep: physics, sensors, leader and
//! followers as real processes.

use caravan_tests::{assert_convoy_succeeded, run_convoy};

#[test]
fn lockstep_convoy_reaches_every_goal_without_collision() {
    let run = run_convoy("convoy.toml");
    assert_convoy_succeeded(&run.report["convoy"]);
    // The physics and the sensors take several periods on one grant, and the odometry the
    // encoder ticks of a batch of theirs. (A node that may do so is never started early: a
    // run with `batch = false` overlaps the odometry with the physics, `convoy/batch.rs`.)
    let schedule = &run.report["run"]["schedule"];
    assert!(
        schedule["batched_steps"].as_u64().unwrap() > 0,
        "{schedule}"
    );
    let trajectories = std::fs::read_to_string(run.dir.join("trajectories.svg")).unwrap();
    assert!(trajectories.contains(">1 m</text>"), "a metre scale bar");
    // The gaps and cross-track errors against time, one line per follower in each panel.
    assert_eq!(run.report["convoy"]["series_plot"], "series.svg");
    let series = std::fs::read_to_string(run.dir.join("series.svg")).unwrap();
    for text in [
        "gap to predecessor (m)",
        "cross-track to predecessor",
        "R1",
        "R4",
        "time (s)",
    ] {
        assert!(series.contains(text), "series.svg lacks {text}");
    }
    assert!(
        series.matches("<polyline").count() >= 8,
        "4 followers × 2 panels"
    );
}

#[test]
fn custom_rust_follower_completes_the_convoy() {
    let run = run_convoy("convoy-custom.toml");
    let c = &run.report["convoy"];
    assert_convoy_succeeded(c);
    // The pure-pursuit follower (R2) stays on its predecessor's path.
    let r2 = &c["followers"][1];
    assert_eq!(r2["robot"], 2);
    assert!(
        r2["cross_track_to_predecessor_m"]["mean"].as_f64().unwrap() < 0.05,
        "{r2}"
    );
}

#[path = "convoy/batch.rs"]
mod batch;
#[path = "convoy/containers.rs"]
mod containers;
