//! The runtime's hot paths, in one process: publishing and receiving a small message and a
//! laser scan through Caravan topics (iceoryx2 shared memory underneath), and deciding one
//! message's fate on an emulated link; and a recording's JSON text of a full map (the
//! writer's `write_json`, beside `serde_json` of the typed value).
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

/// A full 512 × 512 map's JSON text, as the recording writer makes it from the bytes and as
/// `serde_json` makes it of the typed value: the same text (a test holds them equal).
fn record_json(c: &mut Criterion) {
    use caravan_schemas::from_json::{message_from_json, write_message};
    use caravan_schemas::{OccupancyGrid, descriptor::Descriptor};
    let descriptor = Descriptor::of::<OccupancyGrid>();
    let mut bytes = descriptor.default_bytes().expect("a default map");
    // Unknown, free and occupied, as a SLAM map has them.
    let cells: Vec<i8> = (0..512 * 512)
        .map(|i| [-1, 0, 0, 0, 100, 37][i % 6])
        .collect();
    let map = serde_json::json!({"width": 512, "height": 512, "data": cells});
    write_message(descriptor.type_name(), &map, &mut bytes).expect("a 512 x 512 map");
    let header = serde_json::json!({"stamp_ns": 1, "seq": 2});
    let mut g = c.benchmark_group("record_json");
    g.measurement_time(Duration::from_secs(5));
    let mut out = Vec::new();
    g.bench_function("map 512x512: write_json", |b| {
        b.iter(|| {
            out.clear();
            descriptor
                .write_json(&bytes, Some(("header", &header)), &mut out)
                .unwrap();
            black_box(out.len());
        })
    });
    let grid = message_from_json::<OccupancyGrid>(&map).expect("a 512 x 512 map");
    g.bench_function("map 512x512: serde_json of the typed value", |b| {
        b.iter(|| {
            let mut value = serde_json::to_value(grid.as_ref()).unwrap();
            value["header"] = header.clone();
            black_box(serde_json::to_vec(&value).unwrap().len());
        })
    });
    g.finish();
}

criterion_group!(benches, topics, link, record_json);
criterion_main!(benches);
