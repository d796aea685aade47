//! Lockstep overlap: nodes of the next tick that share no topic with the unfinished nodes of
//! the current one start early. Nothing a node sees changes, so a run records the same
//! messages with overlap on (the default) and off.

use caravan_tests::{PINGPONG, Scenario, recording};
use serde_json::Value;

/// Every message of the scenario's recording ([`recording::all_messages`]).
fn all_messages(s: &Scenario) -> Vec<(u16, String, u64, Vec<u8>)> {
    let dir = s.run_dirs().pop().expect("a run directory");
    recording::all_messages(&recording::read(&dir.join("record.mcap")))
}

fn run(tag: &str, extra: &[&str]) -> (Scenario, Value) {
    let s = Scenario::new(tag, PINGPONG);
    let out = s.run(extra);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let schedule = s.report()["run"]["schedule"].clone();
    (s, schedule)
}

#[test]
fn overlapping_ticks_records_the_same_messages_as_one_tick_at_a_time() {
    let (on, with) = run("overlap-on", &[]);
    let (off, without) = run("overlap-off", &["--set", "group.overlap=false"]);
    let (with_overlap, without_overlap) = (all_messages(&on), all_messages(&off));
    for topic in ["demo/ping", "demo/pong", "demo/sum", "demo/noise"] {
        assert!(
            with_overlap.iter().any(|m| m.1 == topic),
            "{topic}: nothing recorded"
        );
    }
    recording::assert_same_messages(&with_overlap, &without_overlap);
    // The same advances and steps; only the run with overlap may start a step early.
    assert_eq!(with["advances"], without["advances"], "{with} {without}");
    assert_eq!(with["steps"], without["steps"], "{with} {without}");
    assert!(with["steps"].as_u64().unwrap() > 100, "{with}");
    assert_eq!(without["overlapped_steps"], 0, "{without}");
    assert!(with["overlapped_steps"].is_u64(), "{with}");
}

/// A `[group]` key given a value that is not a boolean is refused naming it, and nothing starts.
fn refused_unless_boolean(key: &str, value: &str) {
    let s = Scenario::new(
        &format!("{key}-bad"),
        &format!("{key} = {value}\n{PINGPONG}"),
    );
    let out = s.run(&[]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(key), "{err}");
    assert!(s.run_dirs().is_empty(), "a run directory was made: {err}");
}

#[test]
fn overlap_must_be_a_boolean() {
    refused_unless_boolean("overlap", "\"yes\"");
}

#[test]
fn batch_must_be_a_boolean() {
    refused_unless_boolean("batch", "1");
}
