//! The reliability issue's third round: values that named neither key nor `--set`, the
//! hosts' new launch-file keys, seed ranges past the cap, every command's exit code for bad
//! input, and a recording's damaged chunk named by `caravan info`.

use caravan_tests::{
    PINGPONG, Scenario, caravan, launch_with_set, realtime_ping_pong, workspace_bin, workspace_root,
};
use std::process::{Child, Command, Output};

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// `out` is bad input: exit 2, `expected` in its message, no panic.
fn assert_bad_input(args: &[&str], out: &Output, expected: &str) {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert!(
        err.contains(expected),
        "{args:?}: expected '{expected}' in {err}"
    );
    assert!(!err.contains("panicked"), "{args:?}: {err}");
}

/// A realtime ping-pong group, running until [`stop`].
fn running(tag: &str) -> (Scenario, Child) {
    let s = Scenario::new(tag, &realtime_ping_pong("10min"));
    let child = s.start_realtime(2);
    (s, child)
}

fn stop(mut child: Child) {
    // SAFETY: signalling our own child.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    assert!(child.wait().unwrap().success());
}

/// `caravan topic pub MESSAGE` into a running group: bad input whatever is wrong with the
/// message (each case below), exit 2 naming it.
fn publish_refused(tag: &str, message: &str, expected: &str) {
    let (s, child) = running(tag);
    let args = [
        "topic",
        "pub",
        "demo/ping",
        message,
        "--group",
        &s.group.name,
    ];
    let out = caravan(&args);
    stop(child);
    assert_bad_input(&args, &out, expected);
}

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

/// Found by `fuzz_scenario_params_never_panic`: serde names no key inside the IMU driver's
/// tagged scenario, and the launcher found the key by the value quoted (a string, a number),
/// so an array, a table or a boolean named only the file's line. Each names the key and its
/// `--set` now.
#[test]
fn a_param_of_the_wrong_kind_set_on_the_command_line_names_the_key_and_the_set() {
    for (set, expected) in [
        (
            "process.driver.params.angle_deg=[1, 2]",
            "invalid type: sequence",
        ),
        (
            "process.driver.params.angle_deg={ a = 1 }",
            "invalid type: map",
        ),
        (
            "process.driver.params.angle_deg=true",
            "invalid type: boolean `true`",
        ),
        (
            "args.angle_deg=[1, 2]",
            "set by --set args.angle_deg=[1, 2]",
        ),
    ] {
        let (code, err) = launch_with_set("imu/tilt.toml", "1s", set);
        assert_eq!(code, 2, "{set}: {err}");
        for part in ["process 'driver', key 'angle_deg'", expected] {
            assert!(err.contains(part), "{set}: expected '{part}' in {err}");
        }
        if set.starts_with("process.") {
            assert!(err.contains(&format!("--set {set}:")), "{set}: {err}");
        }
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

#[test]
fn topic_pub_of_malformed_json_exits_2() {
    publish_refused("pub-json", r#"{"x": 1"#, "the message is not JSON");
}

#[test]
fn topic_pub_of_an_unknown_field_exits_2() {
    publish_refused("pub-field", r#"{"q": 1}"#, "Pose2D has no field 'q'");
}

#[test]
fn topic_pub_of_a_field_of_the_wrong_type_exits_2() {
    publish_refused("pub-type", r#"{"x": "a"}"#, "x: expected f64, found \"a\"");
}

#[test]
fn clean_of_a_running_group_exits_2_and_leaves_it_running() {
    let (s, child) = running("clean-running");
    let args = ["clean", "--group", &s.group.name];
    let out = caravan(&args);
    let listed = caravan(&["node", "list", "--group", &s.group.name]);
    stop(child);
    assert_bad_input(&args, &out, "is running; stop it first");
    assert!(listed.status.success(), "{}", stderr(&listed));
}

#[test]
fn docs_params_of_a_root_without_docs_exits_2() {
    let dir = std::env::temp_dir().join(format!("caravan-docs-root-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let root = dir.to_str().unwrap();
    let args = ["docs", "params", "--check", "--root", root];
    let out = caravan(&args);
    let _ = std::fs::remove_dir_all(&dir);
    assert_bad_input(&args, &out, "no docs/ directory");
}

#[test]
fn docs_params_of_a_marker_without_its_end_exits_2() {
    let dir = std::env::temp_dir().join(format!("caravan-docs-marker-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("docs")).unwrap();
    std::fs::write(dir.join("docs/page.md"), "<!-- params:caravan-demo\n").unwrap();
    let root = dir.to_str().unwrap();
    let args = ["docs", "params", "--check", "--root", root];
    let out = caravan(&args);
    let _ = std::fs::remove_dir_all(&dir);
    assert_bad_input(
        &args,
        &out,
        "docs/page.md: a '<!-- params:' marker without '-->'",
    );
}

/// Where the first chunk record of the MCAP file `bytes` starts and ends.
fn first_chunk(bytes: &[u8]) -> std::ops::Range<usize> {
    let mut at = 8;
    loop {
        let len = u64::from_le_bytes(bytes[at + 1..at + 9].try_into().unwrap()) as usize;
        if bytes[at] == 0x06 {
            return at..at + 9 + len;
        }
        at += 9 + len;
    }
}

/// `caravan info` read the summary only and printed the normal table for a recording with
/// 64 bytes of 0xFF in a chunk (play and resim refused it). It reads every chunk now, checks
/// its CRC, and names the file and the chunk.
#[test]
fn info_of_a_recording_with_64_bytes_of_0xff_in_a_chunk_names_the_damaged_chunk() {
    let s = Scenario::new("info-crc", PINGPONG);
    let out = s.run(&["--duration", "2s"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let mcap = s.run_dirs().pop().unwrap().join("record.mcap");
    let mut bytes = std::fs::read(&mcap).unwrap();
    let chunk = first_chunk(&bytes);
    assert!(chunk.len() > 400, "{chunk:?}");
    bytes[chunk.start + 200..chunk.start + 264].fill(0xFF);
    std::fs::write(&mcap, &bytes).unwrap();
    let file = mcap.to_str().unwrap();
    let named = format!(
        "{file}: chunk 1 of 1 (bytes {} to {}, log times 0.000 to ",
        chunk.start,
        chunk.end - 1
    );
    for args in [vec!["info", file], vec!["info", "--json", file]] {
        let out = caravan(&args);
        assert_bad_input(&args, &out, &named);
        assert!(stderr(&out).contains(") is damaged: "), "{}", stderr(&out));
        assert!(out.stdout.is_empty(), "{args:?} printed a table");
    }
    // The readers of every message name the chunk too, not a message it garbled.
    let bag = s.dir.join("bag");
    let runs = s.dir.join("resim");
    let resim = [
        "resim",
        file,
        "--node",
        "pong",
        "--runs-dir",
        runs.to_str().unwrap(),
    ];
    let export = ["export", "--ros2", file, bag.to_str().unwrap()];
    for args in [&resim[..], &export[..]] {
        let out = caravan(args);
        assert_bad_input(args, &out, &named);
        assert!(!stderr(&out).contains("not JSON"), "{}", stderr(&out));
    }
    assert!(!bag.exists() && !runs.exists());
}

/// `caravan schemas -o` into a folder that does not exist exited 1, as a failure while
/// writing; it is bad input (exit 2) naming the folder, found before anything is generated.
#[test]
fn schemas_into_a_missing_folder_exits_2_naming_the_folder() {
    let dir = std::env::temp_dir().join(format!("caravan-schemas-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let file = dir.join("missing/caravan_schemas.py");
    let f = file.to_str().unwrap();
    let args = ["schemas", "--python", "-o", f];
    let out = caravan(&args);
    let folder = format!(
        "the folder {} does not exist",
        dir.join("missing").display()
    );
    assert_bad_input(&args, &out, &folder);
    assert!(!dir.exists());
    // A folder given as the file: the same.
    let tmp = std::env::temp_dir();
    let args = ["schemas", "--layout", "-o", tmp.to_str().unwrap()];
    assert_bad_input(
        &args,
        &caravan(&args),
        "is a folder; name the file to write",
    );
}
