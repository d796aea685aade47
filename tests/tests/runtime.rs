//! The runtime foundation across real processes and real shared memory.

use caravan_lockstep::Scheduler;
use caravan_tests::{TestGroup, terminate, test_node, wait_with_cpu};
use serde_json::json;
use std::io::{BufRead, BufReader};
use std::process::{Child, Stdio};
use std::time::Duration;

/// Starts a subscriber node and returns once it reports being subscribed.
fn start_subscriber(group: &str, topic: &str, count: u64, value: f64) -> Child {
    let mut child = test_node(
        group,
        "sub",
        "subscribe",
        json!({"topic": topic, "count": count, "value": value}),
    )
    .stdout(Stdio::piped())
    .spawn()
    .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.as_mut().unwrap())
        .read_line(&mut line)
        .unwrap();
    assert_eq!(line.trim(), "ready", "subscriber did not start");
    child
}

fn finish(child: Child) -> (bool, String) {
    let out = child.wait_with_output().unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr),
    )
}

#[test]
fn hundred_thousand_messages_arrive_gap_free() {
    let group = TestGroup::new("lossless");
    let group = &group.name;
    let sub = start_subscriber(group, "bulk", 100_000, 7.0);
    let status = test_node(
        group,
        "pub",
        "publish",
        json!({"topic": "bulk", "count": 100_000, "value": 7.0}),
    )
    .status()
    .unwrap();
    assert!(status.success());
    let (ok, out) = finish(sub);
    assert!(ok, "{out}");
    assert!(out.contains("received 100000 missed 0"), "{out}");
}

#[test]
fn groups_with_the_same_topic_names_do_not_cross_talk() {
    let (ga, gb) = (TestGroup::new("iso-a"), TestGroup::new("iso-b"));
    let (a, b) = (&ga.name, &gb.name);
    let sub_a = start_subscriber(a, "shared/name", 1000, 1.0);
    let sub_b = start_subscriber(b, "shared/name", 1000, 2.0);
    let pub_a = test_node(
        a,
        "pub",
        "publish",
        json!({"topic": "shared/name", "count": 1000, "value": 1.0}),
    )
    .spawn()
    .unwrap();
    let pub_b = test_node(
        b,
        "pub",
        "publish",
        json!({"topic": "shared/name", "count": 1000, "value": 2.0}),
    )
    .spawn()
    .unwrap();
    for p in [pub_a, pub_b] {
        assert!(p.wait_with_output().unwrap().status.success());
    }
    for sub in [sub_a, sub_b] {
        let (ok, out) = finish(sub);
        // A foreign message would fail the value check; a shared buffer would show gaps.
        assert!(ok, "{out}");
        assert!(out.contains("received 1000 missed 0"), "{out}");
    }
}

#[test]
fn idle_node_costs_almost_no_cpu() {
    let group = TestGroup::new("idle");
    let group = &group.name;
    let mut child = test_node(group, "idle", "idle", json!({})).spawn().unwrap();
    std::thread::sleep(Duration::from_secs(5));
    terminate(&child);
    let (code, cpu) = wait_with_cpu(&mut child);
    assert_eq!(code, 0, "idle node should exit cleanly on SIGTERM");
    // Generous: 2 % of one core over ≥ 5 s is 100 ms, start-up included.
    assert!(
        cpu < Duration::from_millis(100),
        "idle node used {cpu:?} of CPU"
    );
}

#[test]
fn unknown_param_key_is_named_and_fails() {
    let group = TestGroup::new("params");
    let group = &group.name;
    let out = test_node(group, "p", "params", json!({"gain": 1.0, "gian": 2.0}))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("'gian'") && err.contains("unknown key"),
        "{err}"
    );
}

#[test]
fn mistyped_param_names_key_and_expected_type() {
    let group = TestGroup::new("params");
    let group = &group.name;
    let out = test_node(group, "p", "params", json!({"gain": "high"}))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("key 'gain'") && err.contains("expected f64"),
        "{err}"
    );
}

/// Starts the test node `name` in `mode` under the lockstep clock.
fn lockstep_node(group: &str, name: &str, mode: &str, params: serde_json::Value) -> Child {
    test_node(group, name, mode, params)
        .env("CARAVAN_CLOCK", "lockstep")
        .spawn()
        .unwrap()
}

#[test]
fn lockstep_nodes_step_at_granted_times_and_never_see_the_future() {
    let group = TestGroup::new("lockstep");
    let group = &group.name;
    let dir = std::env::temp_dir().join(group);
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("sink.log");
    let config = caravan::group::config(group).unwrap();
    let tick = Duration::from_millis(1);
    let mut scheduler = Scheduler::new(&config, tick).unwrap();
    let spawn = |name: &str, mode: &str, params| lockstep_node(group, name, mode, params);
    let mut source = spawn("source", "lockstep-source", json!({"topic": "ls/pose"}));
    let mut sink = spawn(
        "sink",
        "lockstep-sink",
        json!({"topic": "ls/pose", "out": log.to_str().unwrap()}),
    );
    let alive = |c: &mut Child| c.try_wait().unwrap().is_none();
    let names = vec!["source".to_string(), "sink".to_string()];
    scheduler.wait_for_nodes(&names, |_| Ok(vec![])).unwrap();
    let mut advances = Vec::new();
    while scheduler.next_time_ns().unwrap() <= 1_000_000_000 {
        advances.push(scheduler.advance(|_| Ok(vec![])).unwrap().unwrap());
    }
    scheduler.stop_all().unwrap();
    assert!(source.wait().unwrap().success() && sink.wait().unwrap().success());
    assert!(!alive(&mut source));

    // The 10 Hz source steps at exactly 0, 100, …, 1000 ms; the sink 1 tick after each.
    let source_times: Vec<u64> = advances
        .iter()
        .filter(|a| a.stepped.contains(&"source".into()))
        .map(|a| a.now_ns)
        .collect();
    assert_eq!(
        source_times,
        (0..=10).map(|k| k * 100_000_000).collect::<Vec<_>>()
    );
    let sink_times: Vec<u64> = advances
        .iter()
        .filter(|a| a.stepped.contains(&"sink".into()))
        .map(|a| a.now_ns)
        .collect();
    assert_eq!(
        sink_times,
        (0..10)
            .map(|k| k * 100_000_000 + 1_000_000)
            .collect::<Vec<_>>()
    );

    // Every message was seen exactly one tick after its stamp: never earlier, never lost.
    let seen: Vec<(u64, u64)> = std::fs::read_to_string(&log)
        .unwrap()
        .lines()
        .map(|l| {
            let mut it = l.split(' ').map(|n| n.parse::<u64>().unwrap());
            (it.next().unwrap(), it.next().unwrap())
        })
        .collect();
    assert_eq!(seen.len(), 10);
    for (now, stamp) in seen {
        assert_eq!(now, stamp + 1_000_000);
    }
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn a_scheduled_node_steps_exactly_when_it_asks() {
    let group = TestGroup::new("scheduled");
    let group = &group.name;
    let dir = std::env::temp_dir().join(group);
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("sink.log");
    let config = caravan::group::config(group).unwrap();
    let mut scheduler = Scheduler::new(&config, Duration::from_millis(1)).unwrap();
    let spawn = |name: &str, mode: &str, params| lockstep_node(group, name, mode, params);
    let mut timer = spawn(
        "timer",
        "lockstep-scheduled",
        json!({"topic": "sc/pose", "count": 4}),
    );
    let mut sink = spawn(
        "sink",
        "lockstep-sink",
        json!({"topic": "sc/pose", "out": log.to_str().unwrap()}),
    );
    let names = vec!["timer".to_string(), "sink".to_string()];
    scheduler.wait_for_nodes(&names, |_| Ok(vec![])).unwrap();
    let mut advances = Vec::new();
    // Runs until nobody is due again: the timer stops asking after its fifth step.
    while let Some(a) = scheduler.advance(|_| Ok(vec![])).unwrap() {
        advances.push(a);
    }
    scheduler.stop_all().unwrap();
    assert!(timer.wait().unwrap().success() && sink.wait().unwrap().success());
    let times = |node: &str| -> Vec<u64> {
        advances
            .iter()
            .filter(|a| a.stepped.contains(&node.into()))
            .map(|a| a.now_ns / 1_000_000)
            .collect()
    };
    assert_eq!(times("timer"), vec![0, 10, 40, 90, 160]);
    assert_eq!(times("sink"), vec![1, 11, 41, 91, 161]);
    std::fs::remove_dir_all(dir).ok();
}

/// A message type declared in a crate of its own (here, this test crate), as a scenario
/// declares its messages: the derive describes it from the declaration alone.
mod outside_message {
    use caravan_schemas::describe::{Describe, Element, Kind, Scalar, check};
    use caravan_schemas::{FixedString, Vector3};
    use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};

    #[repr(C)]
    #[derive(Debug, Clone, Copy, ZeroCopySend, PlacementDefault, serde::Serialize, Describe)]
    #[type_name("outside::Beacon")]
    pub struct Beacon {
        pub id: u32,
        pub _reserved: u32,
        pub position: Vector3,
        pub label: FixedString<12>,
    }

    #[test]
    fn a_message_declared_outside_the_schemas_crate_describes_itself() {
        let layout = Beacon::layout();
        assert_eq!(layout.name, "Beacon");
        assert_eq!(layout.type_name, "outside::Beacon");
        assert_eq!(layout.size, size_of::<Beacon>());
        let fields: Vec<(&str, usize, Kind)> = layout
            .fields
            .iter()
            .map(|f| (f.name.as_str(), f.offset, f.kind))
            .collect();
        assert_eq!(
            fields,
            [
                ("id", 0, Kind::Scalar(Scalar::U32)),
                ("_reserved", 4, Kind::Scalar(Scalar::U32)),
                ("position", 8, Kind::Struct("Vector3")),
                ("label_len", 32, Kind::Scalar(Scalar::U32)),
                ("label", 36, Kind::Array(Element::Scalar(Scalar::U8), 12)),
            ]
        );
        check(&layout, &[Vector3::layout()]).unwrap();
    }
}

/// Every `now stamp` line a test node logged.
fn seen(log: &std::path::Path) -> Vec<(u64, u64)> {
    std::fs::read_to_string(log)
        .unwrap()
        .lines()
        .map(|l| {
            let mut it = l.split(' ').map(|n| n.parse::<u64>().unwrap());
            (it.next().unwrap(), it.next().unwrap())
        })
        .collect()
}

/// What [`relay_chain`] leaves: the advances, the scheduler's counts, and the messages `a`
/// and `b` saw, as (its time, the message's stamp) in ms.
type RelayChain = (
    Vec<caravan_lockstep::Advance>,
    caravan_lockstep::ScheduleStats,
    Vec<(u64, u64)>,
    Vec<(u64, u64)>,
);

/// A 10 Hz source, a 100 Hz relay `a` of it, a 100 Hz relay `b` of `a` and a sink stepped
/// by `a`'s messages, stepped for 500 ms (tick 1 ms) with batches on (`a` sends `per_step`
/// messages a step, one more at `burst_ms` if not 0): the advances, the scheduler's counts,
/// and what `a` and `b` saw (ms). The sink and `b` must see each message of `a` once, a
/// tick and a period after it was sent.
fn relay_chain(tag: &str, per_step: u64, burst_ms: u64) -> RelayChain {
    let group = TestGroup::new(tag);
    let group = &group.name;
    let dir = std::env::temp_dir().join(group);
    std::fs::create_dir_all(&dir).unwrap();
    let config = caravan::group::config(group).unwrap();
    let mut scheduler = Scheduler::new(&config, Duration::from_millis(1)).unwrap();
    let end = 500_000_000;
    scheduler.batch_until(end);
    // As a recorder would say once it has looked at them: a batch publishes only to these.
    let topics = ["bt/in", "bt/in/relayed", "bt/in/relayed/relayed"];
    scheduler.know_topics(topics.map(caravan_schemas::lockstep::name_hash));
    let spawn = |name: &str, mode: &str, params| lockstep_node(group, name, mode, params);
    let log = |name: &str| dir.join(format!("{name}.log"));
    let mut children = vec![
        spawn("source", "lockstep-source", json!({"topic": "bt/in"})),
        spawn(
            "a",
            "lockstep-relay",
            json!({"topic": "bt/in", "out": log("a"), "count": per_step, "burst_ms": burst_ms}),
        ),
        spawn(
            "b",
            "lockstep-relay",
            json!({"topic": "bt/in/relayed", "out": log("b")}),
        ),
        spawn(
            "sink",
            "lockstep-sink",
            json!({"topic": "bt/in/relayed", "out": log("sink")}),
        ),
    ];
    let names = ["source", "a", "b", "sink"].map(String::from).to_vec();
    scheduler.wait_for_nodes(&names, |_| Ok(vec![])).unwrap();
    let mut advances = Vec::new();
    while scheduler.next_time_ns().unwrap() <= end {
        advances.push(scheduler.advance(|_| Ok(vec![])).unwrap().unwrap());
    }
    scheduler.stop_all().unwrap();
    for c in &mut children {
        assert!(c.wait().unwrap().success());
    }
    let ms = |v: Vec<(u64, u64)>| -> Vec<(u64, u64)> {
        (v.into_iter())
            .map(|(n, s)| (n / 1_000_000, s / 1_000_000))
            .collect()
    };
    let (a, b, sink) = (
        ms(seen(&log("a"))),
        ms(seen(&log("b"))),
        ms(seen(&log("sink"))),
    );
    // The sink, stepped by `a`'s messages, saw each one tick after it was sent, and `b` one
    // period after: whether `a` took its steps one at a time or several on a grant.
    let relayed = |delay: u64| -> Vec<(u64, u64)> {
        (0..50)
            .flat_map(|k| {
                let n = per_step + (burst_ms > 0 && k * 10 == burst_ms) as u64;
                std::iter::repeat_n((k * 10 + delay, k * 10), n as usize)
            })
            .collect()
    };
    assert_eq!(b, relayed(10));
    assert_eq!(sink, relayed(1));
    std::fs::remove_dir_all(dir).ok();
    (advances, scheduler.stats(), a, b)
}

#[test]
fn a_node_whose_inputs_cannot_change_takes_several_periods_on_one_grant_and_sees_the_same() {
    let (advances, stats, a, b) = relay_chain("batch", 1, 0);
    // `a` reads only the 10 Hz source: between two of its steps `a` takes several periods on
    // one grant, at most 5 (its topic's depth of 8, less a message its readers have not read
    // and room for two more): 10–50 ms, 60–100, 110–150, … 460–500, 40 steps within an
    // earlier one's grant. The source reads nothing: 100–500 ms on one grant (4 more). `b`
    // reads `a`, and follows it: at 20 ms `a` has stepped up to 50, so `b` takes 20–60 on one
    // grant, and so on. The sink, stepped by `a`'s messages, takes those of a batch of `a`
    // on one grant too: 11, 21, 31, 41 and 51 ms, and so on (40 more).
    assert!(stats.batched_steps > 40 + 4 + 30 + 40, "{stats:?}");
    // One wake-up per grant.
    assert_eq!(
        stats.wake_ups,
        stats.steps - stats.batched_steps,
        "{stats:?}"
    );
    let times = |node: &str| -> Vec<u64> {
        (advances.iter())
            .filter(|adv| adv.stepped.contains(&node.into()))
            .map(|adv| adv.now_ns / 1_000_000)
            .collect()
    };
    let every_10ms: Vec<u64> = (0..=50).map(|k| k * 10).collect();
    assert_eq!(times("a"), every_10ms);
    assert_eq!(times("b"), every_10ms);
    let after_a: Vec<u64> = (0..50).map(|k| k * 10 + 1).collect();
    assert_eq!(times("sink"), after_a);
    assert_eq!(stats.steps, 6 + 51 + 51 + 50, "{stats:?}");
    // `a` saw each of the source's messages once, at its first step after the message's time:
    // a batch neither shows a message early nor loses one (and `b` and the sink, above).
    let source: Vec<(u64, u64)> = (0..5).map(|k| (k * 100 + 10, k * 100)).collect();
    assert_eq!(a, source);
    assert_eq!(b.len(), 50);
}

#[test]
fn a_node_sending_two_messages_to_a_topic_in_a_step_ends_its_batch_and_takes_no_more() {
    let (advances, stats, _, b) = relay_chain("burst", 2, 0);
    // `a`'s first step sent two messages: it was never granted several periods. Only the
    // source was (100–500 ms on one grant).
    assert_eq!(stats.batched_steps, 4, "{stats:?}");
    assert_eq!(stats.steps, 6 + 51 + 51 + 50, "{stats:?}");
    assert!(advances.iter().all(|adv| adv.stepped.len() <= 4));
    // `b` saw both messages of each of `a`'s steps, one period later (checked in
    // `relay_chain`, as the sink's).
    assert_eq!(b.len(), 100);
}

#[test]
fn a_batch_ends_at_the_step_that_sends_a_topic_two_messages_and_its_readers_miss_nothing() {
    // `a` takes 10–50 ms on one grant; its step at 30 ms sends two messages: the grant ends
    // there, the scheduler takes the report of 30 ms for it, and `a` steps one period at a
    // time from 40 ms on.
    let (advances, stats, _, b) = relay_chain("burst-late", 1, 30);
    let a_at = |ms: u64| {
        (advances.iter())
            .find(|adv| adv.now_ns == ms * 1_000_000)
            .is_some_and(|adv| adv.stepped.contains(&"a".into()))
    };
    assert!((0..=50).all(|k| a_at(k * 10)), "{advances:?}");
    assert_eq!(stats.steps, 6 + 51 + 51 + 50, "{stats:?}");
    // `b` and the sink saw both messages of 30 ms and each other once (in `relay_chain`).
    assert_eq!(b.len(), 51);
    // The source's batch (4 later steps) and `a`'s 20 and 30 ms, at least.
    assert!(stats.batched_steps >= 4 + 2, "{stats:?}");
}
