//! Physical ranges of params: a number is finite and within what the experiment can mean, or
//! the process refuses it in its `setup` (before the group starts, under the launcher's
//! check) with one message naming the key, the range and the unit:
//! `key 'hold_s': must be between 0.1 and 86400 s, got 1e308`. Every process checks its
//! params through these, so the messages read alike.

/// `v` when it is a finite number in [`min`, `max`]; else a message naming `key`, the range
/// and `unit` (empty for none).
pub fn between(key: &str, v: f64, min: f64, max: f64, unit: &str) -> Result<f64, String> {
    if v.is_finite() && v >= min && v <= max {
        Ok(v)
    } else {
        Err(format!(
            "key '{key}': must be between {} and {}{}, got {}",
            bound(min),
            bound(max),
            spaced(unit),
            shown(v)
        ))
    }
}

/// `v` when it is a finite number above `min` and at most `max`; else a message naming
/// `key`, the range and `unit`.
pub fn above(key: &str, v: f64, min: f64, max: f64, unit: &str) -> Result<f64, String> {
    if v.is_finite() && v > min && v <= max {
        Ok(v)
    } else {
        Err(format!(
            "key '{key}': must be above {} and at most {}{}, got {}",
            bound(min),
            bound(max),
            spaced(unit),
            shown(v)
        ))
    }
}

/// A bound for a message: six significant digits at most (16 g on 5 kg is 784.8 N, not
/// 784.8000000000001).
pub fn bound(x: f64) -> String {
    let rounded: f64 = format!("{x:.5e}").parse().unwrap_or(x);
    shown(rounded)
}

/// A value for a message as it was written: 1e308 and 1e-300 as such, not as 309 digits.
pub fn shown(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e16).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

fn spaced(unit: &str) -> String {
    if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn between_takes_its_bounds_and_names_the_key_and_range_otherwise() {
        assert_eq!(between("hold_s", 0.1, 0.1, 10.0, "s"), Ok(0.1));
        assert_eq!(between("hold_s", 10.0, 0.1, 10.0, "s"), Ok(10.0));
        for bad in [0.09, 1e308, f64::NAN, f64::INFINITY, -1.0] {
            let e = between("hold_s", bad, 0.1, 10.0, "s").unwrap_err();
            assert!(
                e.starts_with("key 'hold_s': must be between 0.1 and 10 s, got"),
                "{e}"
            );
        }
        let e = between("x", 2.0, 0.0, 1.0, "").unwrap_err();
        assert_eq!(e, "key 'x': must be between 0 and 1, got 2");
        let e = between("x", -1e-300, 0.0, 1.0, "").unwrap_err();
        assert_eq!(e, "key 'x': must be between 0 and 1, got -1e-300");
    }

    #[test]
    fn above_leaves_out_its_lower_bound() {
        assert_eq!(above("f", 1.0, 0.0, 2.0, "N"), Ok(1.0));
        let e = above("f", 0.0, 0.0, 784.800_000_000_000_1, "N").unwrap_err();
        assert_eq!(e, "key 'f': must be above 0 and at most 784.8 N, got 0");
    }
}
