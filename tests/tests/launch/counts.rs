//! The report's topic counts come from the recording's writer, during the run.

use caravan_tests::recording::{all_messages, channels, read};
use caravan_tests::{PINGPONG, Scenario};
use std::collections::BTreeMap;

/// What `run.json` says each topic holds is what the file holds: the same messages, and the
/// same gaps in each source's `seq`; the report shows those numbers.
#[test]
fn the_writers_topic_counts_are_what_the_recording_holds() {
    let s = Scenario::new("counts", PINGPONG);
    let out = s.run(&[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let dir = s.run_dirs().pop().unwrap();
    let facts: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("run.json")).unwrap()).unwrap();
    let mut in_file: BTreeMap<String, (u64, u64)> = BTreeMap::new();
    let mut last_seq: BTreeMap<(String, u64), u64> = BTreeMap::new();
    let file = read(&dir.join("record.mcap"));
    // The Foxglove views (protobuf) are the recorder's own, not the group's topics.
    let channels = channels(&file);
    for (_, topic, _, bytes) in all_messages(&file) {
        if channels[&topic].encoding != "json" {
            continue;
        }
        let header = &serde_json::from_slice::<serde_json::Value>(&bytes).unwrap()["header"];
        let source: u64 = header["source_id"].as_str().unwrap().parse().unwrap();
        let seq = header["seq"].as_u64().unwrap();
        let entry = in_file.entry(topic.clone()).or_default();
        entry.0 += 1;
        if let Some(last) = last_seq.insert((topic, source), seq) {
            entry.1 += seq - last - 1;
        }
    }
    assert!(in_file.len() >= 4, "{in_file:?}");
    let counts = facts["topic_counts"]
        .as_object()
        .expect("topic_counts in run.json");
    let report = s.report();
    for (topic, (messages, gaps)) in &in_file {
        assert_eq!(counts[topic]["messages"], *messages, "{topic}");
        assert_eq!(counts[topic]["gaps"], *gaps, "{topic}");
        let row = report["topics"]
            .as_array()
            .unwrap()
            .iter()
            .find(|t| t["name"] == topic.as_str())
            .unwrap();
        assert_eq!(row["messages"], *messages, "{row}");
    }
    assert_eq!(counts.len(), in_file.len());
}
