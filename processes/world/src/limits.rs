//! Bounds on the lengths read from world files and robot descriptions: finite, positive and
//! not absurd, so a typo (`1e308`, `-0.067`, `0`) is an error naming the key instead of a
//! collider the physics cannot build or a robot blamed for starting inside a wall.

/// The largest extent of a world or of an obstacle in it, m: 10 km, where f32 physics still
/// resolves about a millimetre.
pub const MAX_WORLD_EXTENT_M: f64 = 10_000.0;

/// The largest size of one part of a robot (a link's box, cylinder, capsule or sphere), m.
pub const MAX_PART_SIZE_M: f64 = 100.0;

/// `v` when it is a length in (0, `max`] m; else a message naming `what`.
pub fn length(what: &str, v: f64, max: f64) -> Result<f64, String> {
    if !(v.is_finite() && v > 0.0) {
        Err(format!("{what} must be positive, got {v}"))
    } else if v > max {
        Err(format!(
            "{what} is {v} m, more than the {max} m Caravan accepts"
        ))
    } else {
        Ok(v)
    }
}

/// `v` when it is a coordinate within ±`max` m (or an angle within ±`max` rad); else a
/// message naming `what`. Checked before anything is placed, so that a NaN centre is blamed
/// on its key, not on the goal or robot it seems to overlap.
pub fn coordinate(what: &str, v: f64, max: f64) -> Result<f64, String> {
    if v.is_finite() && v.abs() <= max {
        Ok(v)
    } else {
        Err(format!(
            "{what} must be a finite number within ±{max}, got {v}"
        ))
    }
}

/// The largest angle read, rad: a thousand turns; past it the trigonometry loses the angle.
pub const MAX_ANGLE_RAD: f64 = 6283.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coordinates_are_finite_and_bounded() {
        assert_eq!(coordinate("x", -3.0, 10.0), Ok(-3.0));
        for bad in [f64::NAN, f64::NEG_INFINITY, 11.0, -1e308] {
            assert!(
                coordinate("x", bad, 10.0)
                    .unwrap_err()
                    .contains("x must be"),
                "{bad}"
            );
        }
    }

    #[test]
    fn lengths_are_positive_finite_and_bounded() {
        assert_eq!(length("r", 0.5, 1.0), Ok(0.5));
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY, 2.0] {
            assert!(length("r", bad, 1.0).is_err(), "{bad}");
        }
    }
}
