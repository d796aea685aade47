//! The runtime's hot paths, in one process: publishing and receiving a small message and a
//! laser scan through Caravan topics (iceoryx2 shared memory underneath), and deciding one
//! message's fate on an emulated link.
//!
//!     cargo bench -p caravan --bench topics

use caravan::network::{Jitter, LinkProfile, LinkQueue, MessageId};
use caravan::{Node, Topic};
use caravan_schemas::{LaserScan, Pose2D};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::Duration;

fn topics(c: &mut Criterion) {
    let group = format!("bench-topics-{}", std::process::id());
    let node = Node::builder(&group, "bench").build().expect("node");
    let pose_pub = node.publisher(&Topic::<Pose2D>::new("bench/pose")).unwrap();
    let pose_sub = node
        .subscriber(&Topic::<Pose2D>::new("bench/pose"))
        .unwrap();
    let scan_pub = node
        .publisher(&Topic::<LaserScan>::new("bench/scan"))
        .unwrap();
    let scan_sub = node
        .subscriber(&Topic::<LaserScan>::new("bench/scan"))
        .unwrap();
    let mut g = c.benchmark_group("topics");
    g.measurement_time(Duration::from_secs(3));
    g.bench_function("pose publish + receive (copy, 24 B)", |b| {
        b.iter(|| {
            pose_pub
                .publish(&Pose2D {
                    x: 1.0,
                    y: 2.0,
                    theta: 0.5,
                })
                .unwrap();
            black_box(pose_sub.receive().unwrap().map(|m| m.x));
        })
    });
    g.bench_function("scan loan + send + receive (zero-copy, 8.7 KB)", |b| {
        b.iter(|| {
            let mut scan = scan_pub.loan().unwrap();
            scan.beam_count = 682;
            scan.ranges[..682].fill(1.5);
            scan.send().unwrap();
            black_box(scan_sub.receive().unwrap().map(|m| m.ranges[341]));
        })
    });
    g.finish();
    drop((pose_pub, pose_sub, scan_pub, scan_sub, node));
    let _ = caravan::group::remove_resources(&group);
}

fn link(c: &mut Criterion) {
    let link = LinkProfile {
        from: "a".into(),
        to: "b".into(),
        latency_ns: 2_000_000,
        jitter_ns: 8_000_000,
        jitter: Jitter::Normal,
        loss: 0.01,
        spike_probability: 0.01,
        spike_ns: [50_000_000, 100_000_000],
        bandwidth_bps: Some(20_000_000),
    };
    let mut queue = LinkQueue::default();
    let mut seq = 0;
    c.bench_function("link/arrival of one message", |b| {
        b.iter(|| {
            seq += 1;
            let id = MessageId {
                seed: 1,
                source: 2,
                topic: 3,
                seq,
                subscriber: 4,
            };
            black_box(link.arrival(&id, 2_800, seq * 100_000_000, &mut queue))
        })
    });
}

criterion_group!(benches, topics, link);
criterion_main!(benches);
