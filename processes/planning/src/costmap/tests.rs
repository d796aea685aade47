//! Unit tests of the parent module.
use super::*;

const RES: f64 = 0.025;

/// 4 × 2 m of free space with one obstacle cell at (40, 40), the rest unknown.
fn single_obstacle() -> Costmap {
    let (w, h) = (160, 80);
    let mut cells = vec![-1i8; w * h];
    for y in 20..60 {
        for x in 20..60 {
            cells[y * w + x] = 0;
        }
    }
    cells[40 * w + 40] = 100;
    Costmap::from_cells(
        RES,
        Pose2D::default(),
        w,
        h,
        &cells,
        &CostmapParams::default(),
    )
}

#[test]
fn costs_follow_the_inflation_profile() {
    let map = single_obstacle();
    let r = map.robot_radius();
    assert!((r - 0.1445).abs() < 1e-4);
    assert_eq!(map.cost(40, 40), LETHAL);
    // 5 cells away: clearance 4.5 cells = 0.1125 m < r.
    assert_eq!(map.cost(45, 40), INSCRIBED);
    assert_eq!(map.cost(40, 34), INSCRIBED);
    // 10 cells away: clearance 0.2375 m → 252·exp(−10·(0.2375 − 0.1445)) ≈ 99.
    let expected = (252.0 * (-10.0f64 * (0.2375 - r)).exp()).round() as u8;
    assert_eq!(map.cost(50, 40), expected);
    assert!((map.cell_clearance(50, 40) - 0.2375).abs() < 1e-6);
    // Monotonically decaying away from the obstacle.
    let profile: Vec<u8> = (41..60).map(|x| map.cost(x, 40)).collect();
    assert!(profile.windows(2).all(|w| w[0] >= w[1]), "{profile:?}");
    // Known free and far: free. Unknown and far: the unknown cost.
    assert_eq!(map.cost(22, 58), FREE);
    assert_eq!(map.cost(150, 5), map.params().unknown_cost);
    assert_eq!(map.clearance(150.0 * RES, 5.0 * RES), map.max_clearance());
}

#[test]
fn world_cell_round_trip_and_off_map() {
    let map = single_obstacle();
    assert_eq!(map.world_to_cell(1.0125, 1.0125), Some((40, 40)));
    let (x, y) = map.cell_to_world(40, 40);
    assert!((x - 1.0125).abs() < 1e-12 && (y - 1.0125).abs() < 1e-12);
    assert!(map.is_lethal(x, y));
    assert_eq!(map.world_to_cell(-0.01, 0.5), None);
    assert_eq!(map.world_to_cell(4.0, 0.5), None);
    assert!(map.is_lethal(4.1, 0.5));
    assert_eq!(map.clearance(4.1, 0.5), 0.0);
    assert_eq!(map.cost_at(4.1, 0.5), None);
}

#[test]
fn window_covers_known_cells_plus_margin() {
    let map = single_obstacle();
    let w = map.known_window();
    // Known cells span 20..60; the margin is 24 cells (0.55 m / 0.025 m + 1½, rounded
    // up), clipped at the grid's edges (160 × 80).
    assert_eq!(
        w,
        CellWindow {
            x0: 0,
            y0: 0,
            w: 84,
            h: 80
        }
    );
}

#[test]
fn rotated_origin_is_respected() {
    let (w, h) = (40, 20);
    let mut cells = vec![0i8; w * h];
    cells[5 * w + 10] = 100;
    let origin = Pose2D {
        x: 1.0,
        y: 2.0,
        theta: core::f64::consts::FRAC_PI_2,
    };
    let map = Costmap::from_cells(RES, origin, w, h, &cells, &CostmapParams::default());
    // Cell (10, 5) centre: map frame (0.2625, 0.1375) → world (1 − 0.1375, 2 + 0.2625).
    assert_eq!(map.world_to_cell(0.8625, 2.2625), Some((10, 5)));
    assert_eq!(map.cost_at(0.8625, 2.2625), Some(LETHAL));
    let (minx, miny, maxx, maxy) = map.bounds();
    assert!((minx - 0.5).abs() < 1e-9 && (maxx - 1.0).abs() < 1e-9);
    assert!((miny - 2.0).abs() < 1e-9 && (maxy - 3.0).abs() < 1e-9);
}

#[test]
fn invalid_resolution_gives_an_empty_map() {
    let map = Costmap::from_cells(
        0.0,
        Pose2D::default(),
        4,
        4,
        &[0; 16],
        &CostmapParams::default(),
    );
    assert_eq!((map.width(), map.height()), (0, 0));
    assert!(map.is_lethal(0.0, 0.0));
}

#[test]
fn params_validate_and_deserialise_strictly() {
    assert!(CostmapParams::default().validate().is_ok());
    let bad = CostmapParams {
        inflation_radius: 0.1,
        ..CostmapParams::default()
    };
    assert!(bad.validate().unwrap_err().contains("inflation_radius"));
    let p: CostmapParams = toml::from_str("inflation_radius = 0.4").unwrap();
    assert_eq!(p.inflation_radius, 0.4);
    assert_eq!(p.occupied_threshold, 65);
    assert!(toml::from_str::<CostmapParams>("inflation = 0.4").is_err());
}
