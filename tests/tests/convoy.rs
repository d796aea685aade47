//! The five-robot reference convoy, end to end in lockstep: physics, sensors, leader and
//! followers as real processes.

use caravan_tests::{assert_convoy_succeeded, run_convoy};

#[test]
fn lockstep_convoy_reaches_every_goal_without_collision() {
    let run = run_convoy("convoy.toml");
    assert_convoy_succeeded(&run.report["convoy"]);
    assert!(run.dir.join("trajectories.svg").exists());
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
