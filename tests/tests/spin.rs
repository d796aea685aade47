//! Spin, then park (`spin` in `[group]` or a `[[process]]`): a node looks for its next message
//! or grant for a bounded time before it sleeps. It changes when a node wakes, never what it
//! sees: a lockstep run records the same messages, and a realtime pong still answers every ping.

use caravan_tests::{PINGPONG, Scenario, assert_refused, realtime_ping_pong, recording};

fn recorded(s: &Scenario) -> Vec<(u16, String, u64, Vec<u8>)> {
    let out = s.run(&[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let dir = s.run_dirs().pop().expect("a run directory");
    recording::all_messages(&recording::read(&dir.join("record.mcap")))
}

#[test]
fn a_spinning_lockstep_group_records_the_same_messages_as_a_sleeping_one() {
    let sleeping = recorded(&Scenario::new("spin-off", PINGPONG));
    // The scheduler and every node spin; pong spins longer, by its own key.
    let spinning = PINGPONG.replacen(
        "record = [\"demo/*\"]\n",
        "record = [\"demo/*\"]\nspin = \"200us\"\n",
        1,
    );
    let spinning = spinning.replacen(
        "on = \"demo/ping\"\n",
        "on = \"demo/ping\"\nspin = \"1ms\"\n",
        1,
    );
    let spinning = recorded(&Scenario::new("spin-on", &spinning));
    assert!(
        spinning.iter().any(|m| m.1 == "demo/pong"),
        "nothing recorded"
    );
    recording::assert_same_messages(&spinning, &sleeping);
}

#[test]
fn a_spinning_realtime_pong_answers_every_ping() {
    let body = realtime_ping_pong("2s").replacen(
        "on = \"demo/ping\"\n",
        "on = \"demo/ping\"\nspin = \"500us\"\n",
        1,
    );
    let messages = recorded(&Scenario::new("spin-rt", &body));
    let count = |topic: &str| messages.iter().filter(|m| m.1 == topic).count();
    let (pings, pongs) = (count("demo/ping"), count("demo/pong"));
    assert!(pings >= 10, "{pings} pings");
    // The last ping may still be on its way when the group stops.
    assert!(
        pongs + 1 >= pings && pongs <= pings,
        "{pings} pings, {pongs} pongs"
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
