//! `[[include]]`: arguments, `set`, merging, and errors named in the right file.

use super::*;

/// An included file; line numbers in the tests refer to it.
const CONVOY: &str = r#"[args]
localisation = "estimated"

[group]
name = "convoy"
clock = "realtime"
seed = 5

[hosts.sim]
[hosts.rpi-0]
cpu_slowdown = 12.0

[[links]]
between = ["rpi-*", "sim"]

[[process]]
name = "physics"
exec = "caravan-physics"
host = "sim"
rate = "500Hz"
params = { localisation = "$(arg localisation)" }

[[process]]
name = "sensor-0"
exec = "bin/sensor"
host = "sim"
"#;

/// Includes `base/convoy.toml`; line numbers in the tests refer to it.
const TOP: &str = r#"[args]
loc = "ideal"

[[include]]
file = "base/convoy.toml"
args = { localisation = "$(arg loc)" }
set = ["process.sensor-0.host=rpi-0", "group.name=convoy-wlan"]

[group]
seed = 3

[hosts.sim]
cpu_slowdown = 2.0

[[process]]
name = "planner"
exec = "planner"
on = "robot/0/scan"
"#;

fn convoy_files(top: &str) -> PathBuf {
    use std::os::unix::fs::PermissionsExt;
    let dir = write_files(&[("top.toml", top), ("base/convoy.toml", CONVOY)]);
    let sensor = dir.join("base/bin/sensor");
    std::fs::create_dir_all(sensor.parent().unwrap()).unwrap();
    std::fs::write(&sensor, "#!/bin/sh\n").unwrap();
    std::fs::set_permissions(&sensor, std::fs::Permissions::from_mode(0o755)).unwrap();
    dir
}

fn names(lf: &LaunchFile) -> Vec<&str> {
    lf.processes.iter().map(|p| p.name.as_str()).collect()
}

#[test]
fn launch_include_with_args_and_set() {
    let dir = convoy_files(TOP);
    let lf = load_in(&dir, "top.toml", &[]).unwrap();
    assert_eq!(names(&lf), ["physics", "sensor-0", "planner"]);
    // The included file's group is the default; its `set` changed it; the top file wins.
    assert_eq!(lf.group.name, "convoy-wlan");
    assert_eq!(lf.group.seed, 3);
    assert_eq!(lf.group.clock, ClockMode::Realtime);
    // The included file's arguments come from the include's args.
    let physics = &lf.processes[0];
    assert_eq!(physics.params, serde_json::json!({"localisation": "ideal"}));
    assert_eq!(lf.processes[1].host, "rpi-0");
    // Each process remembers its own file's directory; relative execs start there.
    let base = std::path::absolute(dir.join("base")).unwrap();
    assert_eq!(physics.launch_dir, base);
    assert_eq!(
        lf.processes[1].exec,
        Exec::Command(vec!["bin/sensor".into()])
    );
    assert_eq!(
        lf.processes[2].launch_dir,
        std::path::absolute(&dir).unwrap()
    );
    // Hosts merge key by key, the including file's keys winning.
    assert_eq!(lf.hosts["sim"].cpu_slowdown, Some(2.0));
    assert_eq!(lf.hosts["rpi-0"].cpu_slowdown, Some(12.0));
    assert_eq!(lf.links.len(), 1);

    // --set applies after includes, and args.* sets the top file's arguments.
    let lf = load_in(
        &dir,
        "top.toml",
        &["process.physics.rate=250Hz", "args.loc=estimated"],
    )
    .unwrap();
    assert_eq!(lf.processes[0].rate.as_deref(), Some("250Hz"));
    assert_eq!(
        lf.processes[0].params,
        serde_json::json!({"localisation": "estimated"})
    );
}

#[test]
fn launch_include_resolved_toml_stands_alone() {
    let dir = convoy_files(TOP);
    let lf = load_in(&dir, "top.toml", &[]).unwrap();
    assert!(
        !lf.resolved_toml.contains("include"),
        "{}",
        lf.resolved_toml
    );
    if std::env::var_os("SHOW_RESOLVED").is_some() {
        println!("{}", lf.resolved_toml);
    }
    // Saved beside the included file (its relative exec), it loads to the same group.
    std::fs::write(dir.join("base/resolved.toml"), &lf.resolved_toml).unwrap();
    let again = load_in(&dir, "base/resolved.toml", &[]).unwrap();
    assert_eq!(names(&again), names(&lf));
    assert_eq!(again.group, lf.group);
    assert_eq!(again.hosts, lf.hosts);
    assert_eq!(again.processes[0].params, lf.processes[0].params);
}

#[test]
fn launch_include_group_merge_rules() {
    let a = "[group]\nname = \"a\"\nseed = 1\ngrace = \"1s\"\n[hosts.h]\ncpu_slowdown = 2.0\n[[process]]\nname = \"pa\"\nexec = \"sleep\"\n";
    let b = "[group]\nname = \"b\"\nseed = 2\n[[process]]\nname = \"pb\"\nexec = \"sleep\"\n";
    let top = "[[include]]\nfile = \"a.toml\"\n[[include]]\nfile = \"b.toml\"\n[group]\nname = \"top\"\n[hosts.h]\n[hosts.k]\n[[process]]\nname = \"p\"\nexec = \"sleep\"\n";
    let dir = write_files(&[("top.toml", top), ("a.toml", a), ("b.toml", b)]);
    let lf = load_in(&dir, "top.toml", &[]).unwrap();
    assert_eq!(lf.group.name, "top");
    assert_eq!(lf.group.seed, 2, "a later include wins over an earlier one");
    assert_eq!(lf.group.grace, Duration::from_secs(1));
    assert_eq!(lf.hosts["h"].cpu_slowdown, Some(2.0));
    assert!(lf.hosts.contains_key("k"));
    assert_eq!(names(&lf), ["pa", "pb", "p"]);
    // A file with only includes gets its group from them.
    let dir = write_files(&[
        ("top.toml", "[[include]]\nfile = \"a.toml\"\n"),
        ("a.toml", a),
    ]);
    assert_eq!(load_in(&dir, "top.toml", &[]).unwrap().group.name, "a");
}

#[test]
fn launch_include_errors_name_the_included_file() {
    let dir = convoy_files(TOP);
    std::fs::write(
        dir.join("base/convoy.toml"),
        CONVOY.replace("rate = \"500Hz\"", "rate = \"fast\"\nrat = 1"),
    )
    .unwrap();
    let lines = errors_in(&dir, "top.toml", &[]);
    assert_eq!(
        lines,
        [
            "base/convoy.toml:20: process 'physics', key 'rate': 'fast' is not a rate; write a frequency like \"50Hz\" or a period like \"20ms\"",
            "base/convoy.toml:21: process 'physics', key 'rat': unknown key; did you mean 'rate'?",
        ]
    );
    // Unknown sections and syntax errors too.
    std::fs::write(
        dir.join("base/convoy.toml"),
        format!("{CONVOY}[[proces]]\n"),
    )
    .unwrap();
    assert_eq!(
        errors_in(&dir, "top.toml", &[]),
        ["base/convoy.toml:27: key 'proces': unknown key; did you mean 'process'?"]
    );
    std::fs::write(dir.join("base/convoy.toml"), "[group\n").unwrap();
    let lines = errors_in(&dir, "top.toml", &[]);
    assert!(
        lines[0].starts_with("base/convoy.toml:1:7: TOML syntax error"),
        "{lines:?}"
    );
}

#[test]
fn launch_include_missing_file_names_the_including_line() {
    let dir = convoy_files(&TOP.replace("base/convoy.toml", "base/convoi.toml"));
    let lines = errors_in(&dir, "top.toml", &[]);
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert!(
        lines[0].starts_with(
            "top.toml:5: include 'base/convoi.toml', key 'file': cannot read base/convoi.toml: "
        ),
        "{lines:?}"
    );
}

#[test]
fn launch_include_cycle_names_the_chain() {
    let a = "[group]\nname = \"a\"\n[[include]]\nfile = \"b.toml\"\n";
    let b = "[[include]]\nfile = \"a.toml\"\n[[process]]\nname = \"p\"\nexec = \"sleep\"\n";
    let dir = write_files(&[("a.toml", a), ("b.toml", b)]);
    assert_eq!(
        errors_in(&dir, "a.toml", &[]),
        ["b.toml:2: include 'a.toml', key 'file': include cycle: a.toml → b.toml → a.toml"]
    );
}

#[test]
fn launch_include_duplicate_process_names_both_files() {
    let dir = convoy_files(&TOP.replace("name = \"planner\"", "name = \"physics\""));
    let lines = errors_in(&dir, "top.toml", &[]);
    assert_eq!(
        lines,
        [
            "top.toml:16: process 'physics', key 'name': 'physics' is already the name of an earlier process (base/convoy.toml:17)"
        ]
    );
}

#[test]
fn launch_include_bad_args_and_sets_are_named() {
    let top = TOP
        .replace("localisation = \"$(arg loc)\"", "localisaton = 1")
        .replace(
            "\"group.name=convoy-wlan\"",
            "\"process.phyiscs.rate=1Hz\", \"process.physics.rate=fast\", \"args.x=1\"",
        );
    let dir = convoy_files(&top);
    let lines = errors_in(&dir, "top.toml", &[]);
    assert_eq!(
        lines,
        [
            "top.toml:6: include 'base/convoy.toml', key 'args': base/convoy.toml: declares no argument 'localisaton'; did you mean 'localisation'?",
            "top.toml:7: include 'base/convoy.toml', set 'process.phyiscs.rate=1Hz': no process 'phyiscs'; did you mean 'physics'?",
            "top.toml:7: include 'base/convoy.toml', set 'args.x=1': set applies to the resolved file; pass arguments with args = { … }",
            "top.toml:7: set process.physics.rate=fast: process 'physics', key 'rate': 'fast' is not a rate; write a frequency like \"50Hz\" or a period like \"20ms\"",
        ]
    );
}
