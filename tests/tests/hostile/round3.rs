//! The reliability issue's third round: values that named neither key nor `--set`, the
//! hosts' new launch-file keys, seed ranges past the cap, and every command's exit code for
//! bad input.

use caravan_tests::{launch_with_set, workspace_bin, workspace_root};
use std::process::Command;

#[test]
fn an_argument_of_the_wrong_type_set_on_the_command_line_names_the_key_and_the_set() {
    let (code, err) = launch_with_set("imu/tilt.toml", "1s", "args.angle_deg=steep");
    assert_eq!(code, 2, "{err}");
    for expected in [
        "tilt.toml:",
        "key 'angle_deg'",
        "string \"steep\"",
        "set by --set args.angle_deg=steep",
    ] {
        assert!(err.contains(expected), "expected '{expected}' in {err}");
    }
}

#[test]
fn a_host_lease_out_of_its_range_is_refused_naming_the_set() {
    for (value, expected) in [
        ("100ms", "must be 500ms to 600s, found 100ms"),
        ("2h", "must be 500ms to 600s"),
        ("soon", "host_lease"),
    ] {
        let set = format!("group.host_lease={value}");
        let (code, err) = launch_with_set("convoy/convoy-hosts.toml", "1s", &set);
        assert_eq!(code, 2, "{set}: {err}");
        assert!(err.contains(&format!("--set {set}")), "{set}: {err}");
        assert!(
            err.contains(expected),
            "{set}: expected '{expected}' in {err}"
        );
    }
}

/// `caravan-tracked-terrain` had a seed parser of its own that collected the range before
/// counting it: "capacity overflow". It shares `caravan sweep`'s parser and cap now.
#[test]
fn a_terrain_seed_range_up_to_the_largest_u64_is_refused_not_a_panic() {
    let spec = workspace_root().join("launch/tracked/terrains/hills.toml");
    let out_dir = std::env::temp_dir().join(format!("caravan-seeds-cap-{}", std::process::id()));
    let out = Command::new(workspace_bin("caravan-tracked-terrain"))
        .arg(&spec)
        .args(["--seeds", "0..18446744073709551615", "--out-dir"])
        .arg(&out_dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains("gives 18446744073709551615 seeds, more than the 100000 one command takes"),
        "{err}"
    );
    // Refused before anything was written.
    assert!(!out_dir.exists());
}
