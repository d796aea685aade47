//! The Wilson 95 % score interval of a success rate: sweeps' flags and scenarios' tables of
//! outcomes (passed / stuck / flipped) use the same one.

/// The 97.5 % quantile of the standard normal distribution.
pub const Z975: f64 = 1.959_963_984_540_054;

/// The Wilson 95 % score interval of `successes` out of `n` (n ≥ 1). Unlike the normal
/// approximation it stays inside [0, 1] and is not degenerate at 0 or n successes.
pub fn wilson95(successes: usize, n: usize) -> (f64, f64) {
    assert!(n >= 1 && successes <= n, "wilson95 of {successes}/{n}");
    let (n, p) = (n as f64, successes as f64 / n as f64);
    let z2 = Z975 * Z975;
    let denom = 1.0 + z2 / n;
    let centre = (p + z2 / (2.0 * n)) / denom;
    let half = Z975 / denom * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt();
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn wilson_interval_matches_known_values() {
        let (lo, hi) = wilson95(8, 10);
        assert!(
            close(lo, 0.490, 5e-4) && close(hi, 0.943, 5e-4),
            "{lo} {hi}"
        );
        let (lo, hi) = wilson95(0, 10);
        assert!(lo == 0.0 && close(hi, 0.2775, 1e-4), "{hi}");
        let (lo, hi) = wilson95(3, 3);
        assert!(close(lo, 0.4385, 1e-4) && close(hi, 1.0, 1e-12), "{lo}");
    }
}
