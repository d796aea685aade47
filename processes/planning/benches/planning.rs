//! Planner timings: costmap build, a global plan across a room, one local-planner cycle.
//!
//! Run with `cargo bench -p caravan-planning`. The planner runs inside a 10 Hz lockstep
//! simulation, so each of these must stay far below 100 ms.

use caravan_planning::{
    Costmap, CostmapParams, GlobalParams, GlobalPlanner, LocalParams, LocalPlanner,
};
use caravan_schemas::{OccupancyGrid, Pose2D};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::Duration;

const RES: f64 = 0.025;

/// Sets cells whose centres lie in the rectangle (metres, from the grid's corner).
fn rect(cells: &mut [i8], w: usize, (x0, y0, x1, y1): (f64, f64, f64, f64), value: i8) {
    let h = cells.len() / w;
    for iy in 0..h {
        let cy = (iy as f64 + 0.5) * RES;
        if cy < y0 || cy > y1 {
            continue;
        }
        for ix in 0..w {
            let cx = (ix as f64 + 0.5) * RES;
            if cx >= x0 && cx <= x1 {
                cells[iy * w + ix] = value;
            }
        }
    }
}

/// A `w × h`-cell map: free floor, walls round the edge and a scatter of boxes and walls.
fn cluttered(w: usize, h: usize) -> Vec<i8> {
    let mut cells = vec![0i8; w * h];
    let (wm, hm) = (w as f64 * RES, h as f64 * RES);
    for r in [
        (0.0, 0.0, wm, 0.05),
        (0.0, hm - 0.05, wm, hm),
        (0.0, 0.0, 0.05, hm),
        (wm - 0.05, 0.0, wm, hm),
    ] {
        rect(&mut cells, w, r, 100);
    }
    let mut state = 7u32;
    let mut next = || {
        state = state.wrapping_mul(1_103_515_245).wrapping_add(12345);
        f64::from(state >> 8) / f64::from(1u32 << 24)
    };
    for _ in 0..(w * h / 4000) {
        let (x, y) = (next() * wm, next() * hm);
        let (sx, sy) = (0.1 + 0.5 * next(), 0.1 + 0.5 * next());
        rect(&mut cells, w, (x, y, x + sx, y + sy), 100);
    }
    cells
}

/// The 7 × 5 m room of the convoy experiment, with furniture, and a start and goal in
/// opposite corners.
fn room() -> (Vec<i8>, usize, usize) {
    let (w, h) = (280, 200);
    let mut cells = vec![0i8; w * h];
    let boxes = [
        (0.0, 0.0, 7.0, 0.05),
        (0.0, 4.95, 7.0, 5.0),
        (0.0, 0.0, 0.05, 5.0),
        (6.95, 0.0, 7.0, 5.0),
        // A partition with a door, a table, two cabinets, a pillar.
        (2.3, 0.0, 2.4, 3.6),
        (4.2, 1.5, 5.4, 2.3),
        (4.6, 3.6, 5.0, 5.0),
        (1.0, 3.8, 1.8, 4.2),
        (3.3, 0.8, 3.5, 1.0),
    ];
    for b in boxes {
        rect(&mut cells, w, b, 100);
    }
    (cells, w, h)
}

fn bench(c: &mut Criterion) {
    let params = CostmapParams::default();

    let (w, h) = (512, 512);
    let cells = cluttered(w, h);
    let mut map = Costmap::from_cells(RES, Pose2D::default(), w, h, &cells, &params);
    c.bench_function("costmap/build 512x512 known", |b| {
        b.iter(|| map.update_from_cells(RES, Pose2D::default(), w, h, black_box(&cells)));
    });

    // A SLAM map early on: a 1024² grid of which only the 7 × 5 m room is known.
    let (room_cells, rw, rh) = room();
    let mut grid = caravan_schemas::boxed_placement_new::<OccupancyGrid>();
    grid.resolution = RES;
    grid.width = 1024;
    grid.height = 1024;
    grid.data.fill(-1);
    for y in 0..rh {
        let row = (400 + y) * 1024 + 400;
        grid.data[row..row + rw].copy_from_slice(&room_cells[y * rw..(y + 1) * rw]);
    }
    let mut slam = Costmap::from_grid(&grid, &params);
    c.bench_function("costmap/update 1024x1024 grid, 7x5 m known", |b| {
        b.iter(|| slam.update(black_box(&grid)));
    });

    let room_map = Costmap::from_cells(RES, Pose2D::default(), rw, rh, &room_cells, &params);
    let start = Pose2D {
        x: 0.5,
        y: 0.5,
        theta: 0.0,
    };
    let goal = Pose2D {
        x: 6.5,
        y: 0.5,
        theta: 0.0,
    };
    let mut planner = GlobalPlanner::new(GlobalParams::default());
    let path = planner
        .plan(&room_map, start, goal)
        .expect("room is passable");

    c.bench_function("global/A* across 7x5 m room", |b| {
        b.iter(|| planner.plan(&room_map, black_box(start), goal).unwrap());
    });
    let far = Pose2D {
        x: 6.5,
        y: 4.5,
        ..goal
    };
    c.bench_function("global/A* across 7x5 m room, diagonal", |b| {
        b.iter(|| planner.plan(&room_map, black_box(start), far).unwrap());
    });

    let local = LocalPlanner::new(LocalParams::default());
    let pose = path[10];
    c.bench_function("local/one cycle", |b| {
        b.iter(|| local.command(&room_map, black_box(pose), (0.15, 0.2), &path));
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    targets = bench
}
criterion_main!(benches);
