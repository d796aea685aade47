/// Wraps an angle to (−π, π] (the schemas' one wrap).
pub use caravan_schemas::wrap_angle as wrap;

#[cfg(test)]
mod tests {
    use super::wrap;
    use std::f64::consts::PI;

    #[test]
    fn wraps_into_half_open_interval() {
        assert!((wrap(3.0 * PI) - PI).abs() < 1e-12);
        assert!((wrap(-PI / 2.0) + PI / 2.0).abs() < 1e-12);
        assert!((wrap(2.0 * PI + 0.1) - 0.1).abs() < 1e-12);
        assert!((wrap(-3.0) + 3.0).abs() < 1e-12);
    }
}
