//! Differential drive: body velocity (v, ω) ↔ wheel speeds (the reference's formula).

/// Wheel speeds (left, right) in rad/s for body speed `v` (m/s) and turn rate `omega` (rad/s),
/// with wheel radius `r` and wheel separation `l` (m):
/// ω_R = (2v + l·ω)/(2r), ω_L = (2v − l·ω)/(2r).
pub fn wheel_speeds(v: f64, omega: f64, r: f64, l: f64) -> (f64, f64) {
    (
        (2.0 * v - l * omega) / (2.0 * r),
        (2.0 * v + l * omega) / (2.0 * r),
    )
}

/// Body velocity (v, ω) from wheel speeds (left, right) in rad/s.
pub fn body_velocity(left: f64, right: f64, r: f64, l: f64) -> (f64, f64) {
    (r * (left + right) / 2.0, r * (right - left) / l)
}

#[cfg(test)]
mod tests {
    use super::*;

    const R: f64 = 0.067;
    const L: f64 = 0.172;

    #[test]
    fn reference_examples() {
        let (left, right) = wheel_speeds(0.2, 2.0, R, L);
        assert!(
            (right - 5.552).abs() < 5e-4 && (left - 0.418).abs() < 5e-4,
            "{left} {right}"
        );
        let (left, right) = wheel_speeds(0.2, 0.0, R, L);
        assert!((left - 2.985).abs() < 5e-4 && (right - 2.985).abs() < 5e-4);
    }

    #[test]
    fn inverse_round_trips() {
        let (l, r) = wheel_speeds(0.13, -0.7, R, L);
        let (v, w) = body_velocity(l, r, R, L);
        assert!((v - 0.13).abs() < 1e-12 && (w + 0.7).abs() < 1e-12);
    }
}
