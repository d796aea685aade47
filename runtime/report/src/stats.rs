//! Statistics of a sample: mean, sample standard deviation and the Student-t 95 % interval
//! of the mean, for sweeps' cells and scenarios' tables (the Wilson interval of a rate is in
//! [`crate::wilson`]).

use crate::wilson::Z975;

/// Two-sided 95 % Student-t critical values for 1…30 degrees of freedom.
const T975: [f64; 30] = [
    12.7062, 4.3027, 3.1824, 2.7764, 2.5706, 2.4469, 2.3646, 2.3060, 2.2622, 2.2281, 2.2010,
    2.1788, 2.1604, 2.1448, 2.1314, 2.1199, 2.1098, 2.1009, 2.0930, 2.0860, 2.0796, 2.0739, 2.0687,
    2.0639, 2.0595, 2.0555, 2.0518, 2.0484, 2.0452, 2.0423,
];

/// The 97.5 % quantile of Student's t with `df` degrees of freedom (`df` ≥ 1): a table up to
/// 30, then the Cornish-Fisher expansion around the normal quantile (error < 1e-4 there).
pub fn t975(df: usize) -> f64 {
    assert!(df >= 1, "t quantile needs at least one degree of freedom");
    if df <= T975.len() {
        return T975[df - 1];
    }
    let (z, v) = (Z975, df as f64);
    let (z3, z5, z7) = (z.powi(3), z.powi(5), z.powi(7));
    z + (z3 + z) / (4.0 * v)
        + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * v * v)
        + (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / (384.0 * v * v * v)
}

/// Summary of a sample of one numeric metric.
#[derive(Debug, Clone, PartialEq)]
pub struct Describe {
    pub n: usize,
    pub mean: f64,
    /// Sample standard deviation (n − 1 denominator); `None` for n < 2.
    pub sd: Option<f64>,
    pub min: f64,
    pub max: f64,
    /// mean ± t(0.975, n − 1) · sd / √n; `None` for n < 2.
    pub ci95: Option<(f64, f64)>,
}

/// Describes a non-empty sample.
pub fn describe(xs: &[f64]) -> Describe {
    assert!(!xs.is_empty(), "describe needs a value");
    let n = xs.len();
    let mean = xs.iter().sum::<f64>() / n as f64;
    let sd = (n >= 2).then(|| {
        let ss: f64 = xs.iter().map(|x| (x - mean).powi(2)).sum();
        (ss / (n - 1) as f64).sqrt()
    });
    let ci95 = sd.map(|sd| {
        let half = t975(n - 1) * sd / (n as f64).sqrt();
        (mean - half, mean + half)
    });
    Describe {
        n,
        mean,
        sd,
        min: xs.iter().copied().fold(f64::INFINITY, f64::min),
        max: xs.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        ci95,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn mean_sd_and_t_interval_match_hand_values() {
        // 2, 4, 4, 4, 5, 5, 7, 9: mean 5, sum of squares 32, sd √(32/7) = 2.13809.
        let d = describe(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]);
        assert_eq!(d.n, 8);
        assert_eq!(d.mean, 5.0);
        assert!(close(d.sd.unwrap(), 2.138090, 1e-6), "{d:?}");
        assert_eq!((d.min, d.max), (2.0, 9.0));
        // half width 2.3646 · 2.13809 / √8 = 1.78750
        let (lo, hi) = d.ci95.unwrap();
        assert!(
            close(lo, 3.21250, 1e-4) && close(hi, 6.78750, 1e-4),
            "{d:?}"
        );

        // Three seeds, as in docs/fig9a: 1, 2, 3 → sd 1, half width 4.3027 / √3 = 2.48417.
        let (lo, hi) = describe(&[1.0, 2.0, 3.0]).ci95.unwrap();
        assert!(close(lo, -0.48417, 1e-4) && close(hi, 4.48417, 1e-4));
    }

    #[test]
    fn one_value_has_no_spread() {
        let d = describe(&[3.5]);
        assert_eq!((d.n, d.mean, d.sd, d.ci95), (1, 3.5, None, None));
        let d = describe(&[2.0, 2.0]);
        assert_eq!(d.sd, Some(0.0));
        assert_eq!(d.ci95, Some((2.0, 2.0)));
    }

    #[test]
    fn t_quantiles_join_the_table_smoothly() {
        assert_eq!(t975(1), 12.7062);
        assert!(close(t975(31), 2.0395, 1e-4), "{}", t975(31));
        assert!(close(t975(60), 2.0003, 1e-4), "{}", t975(60));
        assert!(close(t975(120), 1.9799, 1e-4), "{}", t975(120));
        assert!(close(t975(1_000_000), Z975, 1e-5));
    }
}
