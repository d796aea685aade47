//! Unit tests of the parent module.
use super::*;

fn map() -> OccupancyMap {
    OccupancyMap::new(0.1, [0.0, 0.0], 20, 10)
}

#[test]
fn hector_update_factors() {
    assert!((LOG_ODDS_HIT - log_odds(0.9)).abs() < 1e-6);
    assert!((LOG_ODDS_PASS - log_odds(0.4)).abs() < 1e-6);
}

#[test]
fn a_beam_clears_its_path_and_marks_its_end() {
    let mut m = map();
    m.update([0.05, 0.55], &[[1.55, 0.55]], &[true]);
    for ix in 0..15 {
        assert_eq!(m.log_odds(ix, 5), LOG_ODDS_PASS, "cell {ix}");
    }
    assert_eq!(m.log_odds(15, 5), LOG_ODDS_HIT);
    assert!(!m.is_known(16, 5) && !m.is_known(0, 4));
    assert!(m.probability(15, 5) > 0.89 && m.probability(3, 5) < 0.41);
}

#[test]
fn a_cell_takes_one_update_of_each_kind_per_scan() {
    let mut m = map();
    // Three beams from one origin share the near cells; one ends where another passes.
    let ends = [[1.55, 0.55], [1.55, 0.56], [0.85, 0.55]];
    m.update([0.05, 0.55], &ends, &[true, true, true]);
    assert_eq!(m.log_odds(0, 5), LOG_ODDS_PASS);
    // The hit wins over the pass of the longer beams in the same scan.
    assert_eq!(m.log_odds(8, 5), LOG_ODDS_HIT);
    assert_eq!(m.log_odds(15, 5), LOG_ODDS_HIT);
    m.update([0.05, 0.55], &ends[..1], &[true]);
    assert_eq!(m.log_odds(0, 5), 2.0 * LOG_ODDS_PASS);
    assert_eq!(m.log_odds(8, 5), LOG_ODDS_HIT + LOG_ODDS_PASS);
}

#[test]
fn no_return_beams_clear_without_a_hit_and_beams_are_clipped() {
    let mut m = map();
    // Diagonal beam leaving the map through the top edge; the origin is outside too.
    m.update([-0.5, 0.05], &[[0.95, 1.5]], &[true]);
    assert!(m.is_known(0, 5) && m.is_known(4, 9) && !m.is_known(5, 9));
    assert!((0..20).all(|ix| (0..10).all(|iy| m.log_odds(ix, iy) <= 0.0)));
    m.update([0.05, 0.05], &[[0.95, 0.05]], &[false]);
    assert_eq!(m.log_odds(9, 0), LOG_ODDS_PASS);
    // Entirely outside: nothing happens.
    let before = m.log_odds.clone();
    m.update([-1.0, -1.0], &[[-0.5, 3.0]], &[true]);
    assert_eq!(before, m.log_odds);
}

#[test]
fn log_odds_are_clamped() {
    let mut m = map().with_updates(0.9, 0.4, 5.0);
    for _ in 0..10 {
        m.update([0.05, 0.05], &[[0.55, 0.05]], &[true]);
    }
    assert_eq!(m.log_odds(5, 0), 5.0);
    assert!((m.log_odds(0, 0) - 10.0 * LOG_ODDS_PASS).abs() < 1e-5);
    for _ in 0..10 {
        m.update([0.05, 0.05], &[[0.55, 0.05]], &[true]);
    }
    assert_eq!(m.log_odds(0, 0), -5.0);
}

#[test]
fn interpolation_and_gradient_match_finite_differences() {
    let mut m = map();
    for (k, l) in m.log_odds.iter_mut().enumerate() {
        *l = ((k * 7919) % 13) as f32 * 0.5 - 3.0;
        m.prob[k] = probability_of(*l);
    }
    // At a cell centre the value is the cell's.
    let (v, _, _) = m.interpolated(0.75, 0.35).unwrap();
    assert!((v - m.probability(7, 3) as f64).abs() < 1e-6);
    let h = 1e-6;
    for &(x, y) in &[(0.731, 0.412), (1.234, 0.777), (0.09, 0.06)] {
        let (v, dx, dy) = m.interpolated(x, y).unwrap();
        let ddx = (m.interpolated(x + h, y).unwrap().0 - v) / h;
        let ddy = (m.interpolated(x, y + h).unwrap().0 - v) / h;
        assert!(
            (dx - ddx).abs() < 1e-3 && (dy - ddy).abs() < 1e-3,
            "{x} {y}"
        );
    }
    assert!(m.interpolated(0.04, 0.5).is_none());
    assert!(m.interpolated(1.96, 0.5).is_none());
}

#[test]
fn grid_values() {
    let mut m = map();
    m.update([0.05, 0.55], &[[1.55, 0.55]], &[true]);
    let mut g = caravan_schemas::boxed_placement_new::<OccupancyGrid>();
    m.write_grid(&mut g);
    assert_eq!((g.width, g.height, g.resolution), (20, 10, 0.1));
    // Occupied (p = 0.9), and the beam's only end point: reflection rate 1.
    assert_eq!(g.get(15, 5), Some(100));
    assert_eq!(g.get(3, 5), Some(40));
    assert_eq!(g.get(16, 5), Some(-1));
    let c = m.coarser(4);
    assert_eq!((c.width(), c.height(), c.resolution()), (5, 3, 0.4));
}

#[test]
fn reflection_is_hits_over_exposure_with_sub_cell_hits() {
    let mut m = map().with_reflection(0.1, 1.0);
    // An end point on a cell centre gives all of its hit to that cell.
    m.update([0.05, 0.55], &[[1.55, 0.55]], &[true]);
    assert_eq!(m.reflection(15, 5), 1.0);
    assert_eq!((m.reflection(14, 5), m.reflection(16, 5)), (0.0, 0.0));
    // One on a cell boundary splits it; the cells are exposed twice now.
    m.update([0.05, 0.55], &[[1.5, 0.55]], &[true]);
    assert!((m.reflection(14, 5) - 0.25).abs() < 1e-6);
    assert!((m.reflection(15, 5) - 0.75).abs() < 1e-6);
    // The cell behind the end point is exposed (within the margin), the next one is not.
    assert_eq!(m.reflection(16, 5), 0.0);
    m.update([0.05, 0.55], &[[1.55, 0.55]], &[true]);
    assert!((m.reflection(15, 5) - 2.5 / 3.0).abs() < 1e-6);
    // The interpolated field peaks between the two end points, nearer the one hit twice.
    let at = |x: f64| m.interpolated_reflection(x, 0.55).unwrap();
    assert!(at(1.55).0 > at(1.5).0 && at(1.55).0 > at(1.6).0);
    assert!(at(1.52).1 > 0.0 && at(1.58).1 < 0.0);
    // Saturation: rates at or above it read 1.
    let mut s = map().with_reflection(0.1, 0.25);
    s.update([0.05, 0.55], &[[1.5, 0.55]], &[true]);
    assert_eq!((s.reflection(14, 5), s.reflection(15, 5)), (1.0, 1.0));
    // Several beams ending in one cell in one scan count once.
    let mut t = map().with_reflection(0.1, 1.0);
    t.update([0.05, 0.55], &[[1.55, 0.55], [1.55, 0.56]], &[true, true]);
    assert_eq!(t.reflection(15, 5), 1.0);
}
