//! `[[links]]`: link profiles, host patterns and bandwidths.

use super::*;
use crate::convert::parse_bandwidth;

#[test]
fn launch_bad_link_profiles_are_named() {
    let text = edited(
        "latency = \"6ms\"\n",
        "latency = \"6ms\"\ndistribution = \"gauss\"\nspike = [\"100ms\", \"50ms\"]\nspike_probability = 2.0\n",
    );
    let lines = errors(&text, &[]);
    assert_error(
        &lines,
        "FILE:12: link #1, key 'distribution': 'gauss' is not a jitter distribution; use uniform, normal or exponential",
    );
    assert_error(
        &lines,
        "FILE:13: link #1, key 'spike': the spike's minimum exceeds its maximum",
    );
    assert_error(
        &lines,
        "FILE:14: link #1, key 'spike_probability': must be between 0.0 and 1.0, found 2",
    );
}

#[test]
fn launch_link_pattern_matching_nothing() {
    let lines = errors(&edited("\"rpi-*\", \"sim\"", "\"rpi-*\", \"simm\""), &[]);
    assert_eq!(
        lines,
        [
            "FILE:10: link #1, key 'between': pattern 'simm' matches no declared host; did you mean 'sim'?"
        ]
    );
    let lines = errors(&edited("[\"rpi-*\", \"sim\"]", "[\"rpi-*\"]"), &[]);
    assert_error(
        &lines,
        "FILE:10: link #1, key 'between': expected exactly two host patterns, found 1",
    );
}

#[test]
fn launch_bandwidths() {
    assert_eq!(parse_bandwidth("54Mbit"), Ok(54_000_000));
    assert_eq!(parse_bandwidth("10mbit"), Ok(10_000_000));
    assert_eq!(parse_bandwidth("1Gbit"), Ok(1_000_000_000));
    assert_eq!(parse_bandwidth("500kbit"), Ok(500_000));
    assert_eq!(parse_bandwidth("1.5 Mbit"), Ok(1_500_000));
    for bad in ["", "54", "54MB", "0Mbit", "fast"] {
        assert!(parse_bandwidth(bad).is_err(), "{bad}");
    }
}
