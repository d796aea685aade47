//! Batches (launch key `group.batch`, on by default): a periodic node whose inputs cannot
//! change is granted several periods at once, and wakes once for them; a node stepped by its
//! messages takes them on one grant too. Nothing they or their readers see changes, so
//! neither does the recording.

use caravan_tests::recording::{all_messages, assert_same_messages, read};
use caravan_tests::{ConvoyRun, node, run_convoy_with};

#[test]
fn a_convoy_granted_several_periods_at_once_records_what_it_records_one_period_at_a_time() {
    let batched = run_convoy_with("convoy.toml", "5s", &[]);
    let single = run_convoy_with("convoy.toml", "5s", &["group.batch=false"]);
    let messages = |run: &ConvoyRun| all_messages(&read(&run.dir.join("record.mcap")));
    assert_same_messages(&messages(&single), &messages(&batched));
    let (b, s) = (&batched.report, &single.report);
    let count = |r: &serde_json::Value, key: &str| r["run"]["schedule"][key].as_u64().unwrap();
    // The same times and steps, the physics' 100 Hz steps between two of the agents' (20 Hz),
    // which are all it reads, taken on a few grants: fewer wake-ups.
    for key in ["advances", "steps"] {
        assert_eq!(count(b, key), count(s, key), "{key}");
    }
    assert_eq!(count(s, "batched_steps"), 0);
    // One period at a time, the odometry (a tick after the sensors) starts while the physics
    // still steps; a node that may take a batch never does.
    assert!(count(s, "overlapped_steps") > 0, "{}", s["run"]["schedule"]);
    assert!(count(b, "batched_steps") >= 300, "{}", b["run"]["schedule"]);
    assert_eq!(
        count(b, "wake_ups"),
        count(s, "wake_ups") - count(b, "batched_steps")
    );
    // Every node stepped as often, and one that lost no message one period at a time lost
    // none in batches. (The monitor reads the ground truth at 10 Hz from buffers of 8: it
    // misses most messages either way, a few more or fewer when the physics runs ahead.)
    for n in s["nodes"].as_array().unwrap() {
        let name = n["name"].as_str().unwrap();
        let m = node(b, name);
        assert_eq!(m["steps"], n["steps"], "{name}");
        if n["messages_missed"] == 0 {
            assert_eq!(m["messages_missed"], 0, "{name}");
        }
    }
    let md = std::fs::read_to_string(batched.dir.join("report.md")).unwrap();
    let line = format!(
        "{} taken within a grant of several periods",
        count(b, "batched_steps")
    );
    assert!(md.contains(&line), "{md}");
}
