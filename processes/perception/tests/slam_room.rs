//! The SLAM driven through the synthetic room: it follows the true pose, and walls measured on
//! its map with `survey` are where they should be.

use caravan_perception::synthetic::Room;
use caravan_perception::{Slam, SlamParams, survey};
use caravan_schemas::{OccupancyGrid, Pose2D, boxed_placement_new};
use std::f64::consts::FRAC_PI_2;

/// A robot at 0.2 m/s scanning at 10 Hz: 1 m along x in 0.02 m steps, a quarter turn on the
/// spot in 0.02 rad steps, then 0.5 m along y.
fn path() -> Vec<Pose2D> {
    let pose = |x, y, theta| Pose2D { x, y, theta };
    let turn = (FRAC_PI_2 / 0.02).ceil() as usize;
    (0..=50)
        .map(|k| pose(1.0 + 0.02 * k as f64, 1.0, 0.0))
        .chain((1..=turn).map(|k| pose(2.0, 1.0, FRAC_PI_2 * k as f64 / turn as f64)))
        .chain((1..=25).map(|k| pose(2.0, 1.0 + 0.02 * k as f64, FRAC_PI_2)))
        .collect()
}

/// Runs the SLAM along `path()`; returns the largest position and heading errors and the map.
fn run(noise_seed: Option<u64>) -> (f64, f64, Box<OccupancyGrid>) {
    let room = Room::default();
    let path = path();
    let mut slam = Slam::new(SlamParams::default(), path[0]).unwrap();
    let (mut worst_d, mut worst_a) = (0.0f64, 0.0f64);
    for (k, truth) in path.iter().enumerate() {
        let est = slam.update(&room.scan(truth, 0.0, noise_seed.map(|s| s + k as u64)));
        worst_d = worst_d.max((est.x - truth.x).hypot(est.y - truth.y));
        worst_a = worst_a.max((est.theta - truth.theta).abs());
    }
    let mut grid = boxed_placement_new::<OccupancyGrid>();
    slam.write_grid(&mut grid);
    (worst_d, worst_a, grid)
}

/// Mean signed error of the four wall faces of the 4 m × 3 m room measured on `grid` from
/// free points inside (east, west, north, south), m.
fn face_errors(grid: &OccupancyGrid) -> [f64; 4] {
    let mut sums = [0.0; 4];
    let measure = |from: [f64; 2], dir: [f64; 2], truth: f64| {
        survey::surface_distance(grid, from, dir, 5.0).expect("a wall in reach") - truth
    };
    let ys = [0.6, 0.8, 1.0, 1.2, 1.4, 1.6];
    for y in ys {
        sums[0] += measure([1.5, y], [1.0, 0.0], 2.5) / ys.len() as f64;
        sums[1] += measure([1.5, y], [-1.0, 0.0], 1.5) / ys.len() as f64;
    }
    let xs = [0.8, 1.2, 1.6, 2.0, 2.4];
    for x in xs {
        sums[2] += measure([x, 1.5], [0.0, 1.0], 1.5) / xs.len() as f64;
        sums[3] += measure([x, 1.5], [0.0, -1.0], 1.5) / xs.len() as f64;
    }
    sums
}

/// Without noise, and with the walls exactly on cell boundaries (the map is centred on the
/// start pose, a whole number of cells from each wall), every end point on a wall splits
/// equally between two cells, the field is flat between their centres, and the pose is only
/// pinned down to half a cell (1.25 cm) across each wall.
#[test]
fn slam_follows_noise_free_scans() {
    let (d, a, grid) = run(None);
    let f = face_errors(&grid);
    println!("noise-free: pose error ≤ {d:.4} m, {a:.4} rad; face errors E W N S {f:.4?}");
    assert!(d < 0.02 && a < 0.01, "worst error {d} m, {a} rad");
    assert!(f.iter().all(|e| e.abs() < 0.025), "face errors {f:?}");
}

#[test]
fn slam_follows_noisy_scans_and_keeps_the_map_to_scale() {
    let mut all = Vec::new();
    for seed in [1, 1000] {
        let (d, a, grid) = run(Some(seed));
        assert!(
            d < 0.02 && a < 0.01,
            "seed {seed}: worst error {d} m, {a} rad"
        );
        let f = face_errors(&grid);
        let width = 4.0 + f[0] + f[1];
        let depth = 3.0 + f[2] + f[3];
        println!(
            "seed {seed}: pose error ≤ {d:.4} m, {a:.4} rad; face errors E W N S {f:.4?}; width {width:.4} m, depth {depth:.4} m"
        );
        assert!(
            (width / 4.0 - 1.0).abs() < 0.01,
            "seed {seed}: width {width}"
        );
        assert!(
            (depth / 3.0 - 1.0).abs() < 0.01,
            "seed {seed}: depth {depth}"
        );
        all.extend(f);
    }
    // Each face lies within 2 cm of the truth on average over the probes.
    assert!(all.iter().all(|e| e.abs() < 0.02), "{all:?}");
}
