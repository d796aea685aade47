//! Spin, then park (`spin` in `[group]` or a `[[process]]`): a node looks for its next message
//! or grant for a bounded time before it sleeps. It changes when a node wakes, never what it
//! sees: a lockstep run records the same messages, and a realtime pong still answers every ping.

use caravan_tests::{PINGPONG, Scenario, assert_refused, realtime_ping_pong, recording};

/// Runs the scenario, which must succeed, and returns its run directory.
fn run_ok(s: &Scenario) -> std::path::PathBuf {
    let out = s.run(&[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    s.run_dirs().pop().expect("a run directory")
}

fn recorded(s: &Scenario) -> Vec<(u16, String, u64, Vec<u8>)> {
    let dir = run_ok(s);
    recording::all_messages(&recording::read(&dir.join("record.mcap")))
}

/// `body` with `spin = "SPIN"` after its line `after`, which must be there.
fn with_spin(body: &str, after: &str, spin: &str) -> String {
    assert!(body.contains(after), "no line {after:?} in {body}");
    body.replacen(after, &format!("{after}spin = \"{spin}\"\n"), 1)
}

#[test]
fn a_spinning_lockstep_group_records_the_same_messages_as_a_sleeping_one() {
    let sleeping = recorded(&Scenario::new("spin-off", PINGPONG));
    // The scheduler and every node spin; pong spins longer, by its own key.
    let spinning = with_spin(PINGPONG, "record = [\"demo/*\"]\n", "200us");
    let spinning = with_spin(&spinning, "on = \"demo/ping\"\n", "1ms");
    let spinning = recorded(&Scenario::new("spin-on", &spinning));
    assert!(
        spinning.iter().any(|m| m.1 == "demo/pong"),
        "nothing recorded"
    );
    recording::assert_same_messages(&spinning, &sleeping);
}

#[test]
fn a_spinning_realtime_pong_answers_every_ping() {
    let body = with_spin(&realtime_ping_pong("2s"), "on = \"demo/ping\"\n", "500us");
    let messages = recorded(&Scenario::new("spin-rt", &body));
    let times = |topic: &str| -> Vec<u64> {
        let mut t: Vec<u64> = messages
            .iter()
            .filter(|m| m.1 == topic)
            .map(|m| m.2)
            .collect();
        t.sort();
        t
    };
    let (pings, pongs) = (times("demo/ping"), times("demo/pong"));
    let first_pong = *pongs.first().expect("pong answered nothing");
    // Pings sent before pong subscribed are lost to it, as to any late reader: count from the
    // ping its first answer is for (the last one sent before that answer).
    let answered_from = pings
        .iter()
        .rposition(|&t| t <= first_pong)
        .expect("a ping before the first pong");
    let due = pings.len() - answered_from;
    // The last ping may still be on its way when the group stops.
    assert!(
        pongs.len() + 1 >= due && pongs.len() <= due,
        "{due} pings since pong's first answer, {} pongs",
        pongs.len()
    );
}

#[test]
fn a_spin_past_a_millisecond_or_not_a_duration_is_refused() {
    let s = Scenario::new("spin-bad", PINGPONG);
    for set in ["group.spin=2ms", "process.pong.spin=fast", "group.spin=5"] {
        let out = s.run(&["--set", set]);
        assert_refused(&s, &out, &["key 'spin'"]);
    }
    let out = s.run(&["--set", "group.spin=2ms"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("longer than"), "{err}");
}

#[test]
fn a_process_spin_overrides_the_groups_and_reaches_the_process() {
    let body = r#"clock = "realtime"
duration = "1s"
spin = "1ms"

[[process]]
name = "group-spin"
exec = "sh -c 'echo spin=$CARAVAN_SPIN'"

[[process]]
name = "own-spin"
exec = "sh -c 'echo spin=$CARAVAN_SPIN'"
spin = "20us"
"#;
    let s = Scenario::new("spin-env", body);
    let dir = run_ok(&s);
    let log = |name: &str| {
        let path = dir.join("logs").join(format!("{name}.log"));
        std::fs::read_to_string(&path).unwrap_or_else(|e| {
            let listing: Vec<_> = std::fs::read_dir(&dir)
                .map(|d| d.flatten().map(|e| e.file_name()).collect())
                .unwrap_or_default();
            panic!(
                "{}: {e}; the run directory holds {listing:?}",
                path.display()
            )
        })
    };
    assert_eq!(log("group-spin").trim(), "spin=1000000ns");
    assert_eq!(log("own-spin").trim(), "spin=20000ns");
}
