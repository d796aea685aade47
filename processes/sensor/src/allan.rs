//! Allan deviation of rate samples (overlapping estimator, IEEE Std 952), and reading the
//! noise density and bias instability off it.

use crate::imu_errors::FLICKER_FLOOR;

/// Overlapping Allan deviation of `samples` (equally spaced `dt` s apart) at averaging times
/// of `m` samples, one `(τ, σ)` per `m` with at least two clusters of data.
pub fn allan_deviation(samples: &[f64], dt: f64, ms: &[usize]) -> Vec<(f64, f64)> {
    // θ_k: the integral of the rate up to sample k.
    let mut theta = Vec::with_capacity(samples.len() + 1);
    theta.push(0.0);
    let mut sum = 0.0;
    for y in samples {
        sum += y * dt;
        theta.push(sum);
    }
    let n = theta.len();
    ms.iter()
        .filter(|&&m| m > 0 && 2 * m < n)
        .map(|&m| {
            let tau = m as f64 * dt;
            let terms = n - 2 * m;
            let s: f64 = (0..terms)
                .map(|k| {
                    let d = theta[k + 2 * m] - 2.0 * theta[k + m] + theta[k];
                    d * d
                })
                .sum();
            (tau, (s / (2.0 * tau * tau * terms as f64)).sqrt())
        })
        .collect()
}

/// Cluster sizes spread evenly in log, `per_decade` per decade, from 1 to `max`.
pub fn log_clusters(max: usize, per_decade: usize) -> Vec<usize> {
    let mut out: Vec<usize> = (0..)
        .map(|k| 10f64.powf(k as f64 / per_decade as f64).round() as usize)
        .take_while(|&m| m <= max)
        .collect();
    out.dedup();
    out
}

/// Noise density N and bias instability B read off an Allan deviation: the model
/// σ²(τ) = N²/τ + (0.664·B)² (white noise falling at −½, flicker flat) fitted to σ(τ) for
/// τ ≤ `tau_max`, each point weighted by its relative error, as IEEE Std 952 fits its
/// terms. Both are found together, so neither is biased by the other where they overlap.
/// `None` with fewer than two points or a fit that gives a negative term.
pub fn white_and_flicker(adev: &[(f64, f64)], tau_max: f64) -> Option<(f64, f64)> {
    // Minimise Σ ((x₁/τ + x₂)/σ² − 1)², linear in x₁ = N², x₂ = (0.664·B)².
    let (mut a11, mut a12, mut a22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let mut n = 0;
    for &(tau, s) in adev.iter().filter(|(tau, s)| *tau <= tau_max && *s > 0.0) {
        let (u, v) = (1.0 / (tau * s * s), 1.0 / (s * s));
        a11 += u * u;
        a12 += u * v;
        a22 += v * v;
        b1 += u;
        b2 += v;
        n += 1;
    }
    let det = a11 * a22 - a12 * a12;
    if n < 2 || det <= 0.0 {
        return None;
    }
    let x1 = (b1 * a22 - b2 * a12) / det;
    let x2 = (a11 * b2 - a12 * b1) / det;
    (x1 >= 0.0 && x2 >= 0.0).then(|| (x1.sqrt(), x2.sqrt() / FLICKER_FLOOR))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::Gaussian;

    #[test]
    fn white_noise_falls_as_n_over_root_tau() {
        let (dt, n): (f64, f64) = (0.01, 2e-3);
        let mut g = Gaussian::new(3, 9);
        let samples: Vec<f64> = (0..200_000).map(|_| g.sample(n / dt.sqrt())).collect();
        let adev = allan_deviation(&samples, dt, &log_clusters(10_000, 4));
        let (est, flicker) = white_and_flicker(&adev, 10.0).unwrap();
        assert!((est / n - 1.0).abs() < 0.05, "{est}");
        // No flicker: the fitted floor stays below the white noise at the longest τ.
        assert!(FLICKER_FLOOR * flicker < n / 10f64.sqrt(), "{flicker}");
        // A constant has no Allan deviation.
        let flat = allan_deviation(&[1.0; 1000], dt, &[1, 10, 100]);
        assert!(flat.iter().all(|(_, s)| *s < 1e-12), "{flat:?}");
    }
}
