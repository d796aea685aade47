//! The reliability issue's third round: values that named neither key nor `--set`, and the
//! hosts' new launch-file keys.

use caravan_tests::launch_with_set;

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
