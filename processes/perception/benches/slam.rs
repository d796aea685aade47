//! SLAM cost per scan (682 beams, the URG-04LX) in a synthetic room once the map is built.
//!
//! - `slam_update`: [`Slam::update`] along a closed circle of radius 0.5 m (0.02 m and 0.04 rad
//!   per scan, a robot at 0.2 m/s and 0.4 rad/s scanning at 10 Hz), including the map updates,
//!   which the turn rate triggers every second scan (0.06 rad threshold).
//! - `match_scan`: the three-level scan matching alone, from a guess 3 cm / 0.03 rad off.
//! - `map_update`: writing one scan into the three levels (what a map update adds to a scan).

use caravan_perception::grid::OccupancyMap;
use caravan_perception::matcher::{MatchField, match_scan};
use caravan_perception::slam::scan_to_points;
use caravan_perception::synthetic::Room;
use caravan_perception::{Slam, SlamParams};
use caravan_schemas::{LaserScan, Pose2D};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::Duration;

/// Poses around a circle of radius 0.5 m centred at (1.5, 1.2), 0.02 m apart, heading along
/// the path.
fn circle() -> Vec<Pose2D> {
    let (r, n) = (0.5, (std::f64::consts::TAU * 0.5 / 0.02).round() as usize);
    (0..n)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            Pose2D {
                x: 1.5 + r * a.sin(),
                y: 1.2 - r * a.cos(),
                theta: a,
            }
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let room = Room::default();
    let path = circle();
    let scans: Vec<LaserScan> = path
        .iter()
        .enumerate()
        .map(|(k, p)| room.scan(p, 0.0, Some(k as u64)))
        .collect();
    let mut slam = Slam::new(SlamParams::default(), path[0]).unwrap();
    // Two laps build the map.
    for scan in scans.iter().chain(&scans) {
        slam.update(scan);
    }
    let truth = path[0];
    let est = slam.update(&scans[0]);
    assert!((est.x - truth.x).hypot(est.y - truth.y) < 0.05, "{est:?}");

    let mut group = c.benchmark_group("perception");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    let mut k = 1;
    group.bench_function("slam_update", |b| {
        b.iter(|| {
            let pose = slam.update(black_box(&scans[k]));
            k = (k + 1) % scans.len();
            pose
        })
    });

    let points = scan_to_points(&scans[0], 0.0, 0.1, 5.6);
    let maps: Vec<&OccupancyMap> = (0..3).map(|l| slam.map(l)).collect();
    let guess = Pose2D {
        x: truth.x + 0.03,
        y: truth.y - 0.02,
        theta: truth.theta + 0.03,
    };
    // As the SLAM does: every point on the finest level, every 2nd and 4th on the others.
    let level_points: Vec<Vec<[f64; 2]>> = (0..3)
        .map(|l| points.iter().copied().step_by(1 << l).collect())
        .collect();
    group.bench_function("match_scan", |b| {
        b.iter(|| {
            let mut est = black_box(guess);
            for (level, map) in maps.iter().enumerate().rev() {
                let iterations = if level == 0 { 5 } else { 3 };
                est = match_scan(
                    map,
                    MatchField::Reflection,
                    &level_points[level],
                    est,
                    iterations,
                )
                .pose;
            }
            est
        })
    });

    let mut fresh: Vec<OccupancyMap> = (0..3).map(|l| slam.map(l).clone()).collect();
    let (s, co) = truth.theta.sin_cos();
    let ends: Vec<[f64; 2]> = points
        .iter()
        .map(|p| {
            [
                truth.x + co * p[0] - s * p[1],
                truth.y + s * p[0] + co * p[1],
            ]
        })
        .collect();
    let hits = vec![true; ends.len()];
    group.bench_function("map_update", |b| {
        b.iter(|| {
            for map in &mut fresh {
                map.update([truth.x, truth.y], black_box(&ends), &hits);
            }
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
