//! The braking distance of a run: how far the base travels after the operator asks for a
//! stop (the first zero forward speed on `cmd_vel` after a positive one), from the ground
//! truth, as the reference measured its robot (real 0.02 m, Gazebo 0.3 m).

use crate::crossing::Sample;

/// The robot counts as at rest when it moved less than this over the run's last
/// [`REST_WINDOW_S`], m (chosen: a tenth of a tooth's pitch).
pub const REST_DISTANCE_M: f64 = 0.003;
/// See [`REST_DISTANCE_M`], s.
pub const REST_WINDOW_S: f64 = 0.5;

/// When the operator asked for a stop: the first command of zero forward speed after a
/// positive one; `commands` are (time s, forward speed m/s) in time order.
pub fn stop_time(commands: &[(f64, f64)]) -> Option<f64> {
    let mut moving = false;
    for &(t, v) in commands {
        if v > 0.0 {
            moving = true;
        } else if moving && v == 0.0 {
            return Some(t);
        }
    }
    None
}

/// Horizontal path length of the samples from `from_s` on, m.
fn path_after(samples: &[Sample], from_s: f64) -> f64 {
    let after: Vec<&Sample> = samples.iter().filter(|s| s.t_s >= from_s).collect();
    after
        .windows(2)
        .map(|w| {
            let (a, b) = (w[0].position, w[1].position);
            (b[0] - a[0]).hypot(b[1] - a[1])
        })
        .sum()
}

/// The distance the base travelled from `stop_s` until it came to rest, m; `None` if it was
/// still moving at the end of the samples (the run ended too soon to tell).
pub fn braking_distance(samples: &[Sample], stop_s: f64) -> Option<f64> {
    let end = samples.last()?.t_s;
    if end - stop_s < REST_WINDOW_S || path_after(samples, end - REST_WINDOW_S) > REST_DISTANCE_M {
        return None;
    }
    Some(path_after(samples, stop_s))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(t_s: f64, x: f64) -> Sample {
        Sample {
            t_s,
            position: [x, 1.5, 0.1],
            orientation: [0.0, 0.0, 0.0, 1.0],
        }
    }

    /// 0.4 m/s until 2 s, then slowing at 0.2 m/s² to rest at 4 s: 0.4 m after the stop.
    fn run(end_s: f64) -> Vec<Sample> {
        (0..=(end_s * 100.0) as usize)
            .map(|i| {
                let t = i as f64 * 0.01;
                let x = if t <= 2.0 {
                    0.4 * t
                } else {
                    let d = (t - 2.0).min(2.0);
                    0.8 + 0.4 * d - 0.1 * d * d
                };
                at(t, x)
            })
            .collect()
    }

    #[test]
    fn the_stop_is_the_first_zero_after_moving() {
        let cmds = [(0.0, 0.0), (0.5, 0.4), (1.0, 0.4), (2.0, 0.0), (3.0, 0.0)];
        assert_eq!(stop_time(&cmds), Some(2.0));
        assert_eq!(stop_time(&[(0.0, 0.0), (1.0, 0.0)]), None);
        assert_eq!(stop_time(&[(0.0, 0.3)]), None);
    }

    #[test]
    fn braking_distance_is_the_path_from_the_stop_to_rest() {
        let d = braking_distance(&run(6.0), 2.0).unwrap();
        assert!((d - 0.4).abs() < 1e-3, "{d}");
    }

    #[test]
    fn a_run_that_ends_still_moving_has_no_braking_distance() {
        assert_eq!(braking_distance(&run(3.0), 2.0), None);
        assert_eq!(braking_distance(&run(4.1), 2.0), None);
    }
}
