//! Numbers in Markdown tables.

use serde_json::Value;

/// `v` with `digits` decimals, or "–" when it is not a number.
pub fn num(v: &Value, digits: usize) -> String {
    match v.as_f64() {
        Some(x) => format!("{x:.digits$}"),
        None => "–".into(),
    }
}

/// `p50 / p90 / p99 / max` of a percentiles object.
pub fn quantiles(q: &Value, digits: usize) -> String {
    ["p50", "p90", "p99", "max"]
        .map(|k| num(&q[k], digits))
        .join(" / ")
}

/// `mean / p95 / max` of a statistics object.
pub fn mean_p95_max(v: &Value, digits: usize) -> String {
    ["mean", "p95", "max"]
        .map(|k| num(&v[k], digits))
        .join(" / ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn numbers_and_gaps() {
        assert_eq!(num(&json!(1.23456), 2), "1.23");
        assert_eq!(num(&Value::Null, 2), "–");
        let q = json!({"p50": 1.0, "p90": 2.0, "p99": 3.0});
        assert_eq!(quantiles(&q, 1), "1.0 / 2.0 / 3.0 / –");
    }
}
