//! Checks shared by the tracked processes' params: an error names the key as the user wrote
//! it, under its table.

/// Every value finite and > 0, else an error naming the first that is not, as
/// `'{prefix}{key}'` (the prefix is the key's table, e.g. `keep_line.`, or empty).
pub fn all_positive(prefix: &str, values: &[(&str, f64)]) -> Result<(), String> {
    match values.iter().find(|(_, v)| !(v.is_finite() && *v > 0.0)) {
        Some((key, v)) => Err(format!(
            "key '{prefix}{key}': must be a positive number, got {v}"
        )),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_value_not_positive_and_finite_is_named_with_its_table() {
        assert!(all_positive("", &[("a", 1.0), ("b", 0.5)]).is_ok());
        let e = all_positive("t.", &[("a", 1.0), ("b", 0.0), ("c", -1.0)]).unwrap_err();
        assert_eq!(e, "key 't.b': must be a positive number, got 0");
        assert!(
            all_positive("", &[("n", f64::NAN)])
                .unwrap_err()
                .contains("'n'")
        );
        assert!(all_positive("", &[("i", f64::INFINITY)]).is_err());
    }
}
