//! Process templates: `for = "i in a..b"` and `{i}` in every string of the entry.

use super::*;

/// Line numbers in the tests refer to this file.
const TEMPLATED: &str = r#"[args]
topic = "robot/{i}/scan"
n = 4

[group]
name = "t"

[[process]]
name = "sensor-{i}"
for = "i in 1..$(arg n)"
exec = "sleep"
args = ["--id={i}", "{i}"]
rate = "{i}0Hz"
params = { index = "{i}", prev = "{i-1}", topic = "$(arg topic)", raw = "{{literal}}", nested = { list = ["{i+1}", "x{i}"] } }
env = { ID = "{i}" }

[[process]]
name = "plain"
exec = "sleep"
params = { braces = "{x}" }
"#;

#[test]
fn launch_template_expands_each_value() {
    let lf = load_text(TEMPLATED, &[]).unwrap();
    let names: Vec<&str> = lf.processes.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["sensor-1", "sensor-2", "sensor-3", "plain"]);
    let s2 = &lf.processes[1];
    assert_eq!(s2.args, ["--id=2", "2"]);
    assert_eq!(s2.rate.as_deref(), Some("20Hz"));
    assert_eq!(
        s2.params,
        serde_json::json!({
            "index": 2, "prev": 1, "topic": "robot/2/scan", "raw": "{literal}",
            "nested": {"list": [3, "x2"]}
        })
    );
    assert_eq!(s2.env["ID"], "2");
    // Entries without `for` keep their braces.
    assert_eq!(lf.processes[3].params, serde_json::json!({"braces": "{x}"}));
    assert!(!lf.resolved_toml.contains("for ="), "{}", lf.resolved_toml);
    assert!(lf.resolved_toml.contains("name = \"sensor-3\""));
    // Inclusive ranges, another variable name, and --set of an expanded entry by name.
    let text = TEMPLATED
        .replace("i in 1..$(arg n)", "robot in 1..=2")
        .replace("{i", "{robot");
    let lf = load_text(&text, &["process.sensor-2.params.laser=true"]).unwrap();
    assert_eq!(lf.processes.len(), 3);
    assert_eq!(lf.processes[1].name, "sensor-2");
    assert_eq!(lf.processes[1].params["laser"], true);
    assert!(lf.processes[0].params.get("laser").is_none());
    // The range may come from an argument set on the command line.
    let lf = load_text(TEMPLATED, &["args.n=2"]).unwrap();
    assert_eq!(lf.processes.len(), 2);
}

#[test]
fn launch_template_bad_ranges_are_named() {
    let lines = errors(&TEMPLATED.replace("1..$(arg n)", "1...4"), &[]);
    assert_eq!(
        lines,
        [
            "FILE:10: process 'sensor-{i}', key 'for': 'i in 1...4' is not a template range; write for = \"i in 0..4\" (4 excluded) or \"i in 1..=4\""
        ]
    );
    // The line shows the reference; the message names the --set that gave its value.
    let lines = errors(TEMPLATED, &["args.n=1"]);
    assert_eq!(
        lines,
        [
            "FILE:10: process 'sensor-{i}', key 'for': the range '1..1' is empty (from $(arg n), set by --set args.n=1)"
        ]
    );
    let lines = errors(
        &TEMPLATED.replace("for = \"i in 1..$(arg n)\"", "for = 3"),
        &[],
    );
    assert!(
        lines[0]
            .starts_with("FILE:10: process 'sensor-{i}', key 'for': '3' is not a template range"),
        "{lines:?}"
    );
}

#[test]
fn launch_template_unknown_variable_is_named() {
    let lines = errors(&TEMPLATED.replace("\"{i}0Hz\"", "\"{j}0Hz\""), &[]);
    assert_eq!(
        lines,
        [
            "FILE:13: process 'sensor-{i}', key 'rate': unknown variable 'j' in '{j}'; the template's variable is 'i'"
        ]
    );
    let lines = errors(&TEMPLATED.replace("x{i}", "x{i"), &[]);
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert!(
        lines[0].starts_with("FILE:14: process 'sensor-{i}', key 'params': an unclosed '{'"),
        "{lines:?}"
    );
}

#[test]
fn launch_template_errors_say_which_repetition() {
    let lines = errors(
        &TEMPLATED.replace("\"{i}0Hz\"", "\"{i}0 Hz please\""),
        &["args.n=3"],
    );
    assert_eq!(lines.len(), 2, "{lines:?}");
    assert!(
        lines[0].starts_with(
            "FILE:13: process 'sensor-1' (from the template at FILE:8, i = 1), key 'rate': '10 Hz please' is not a rate"
        ),
        "{lines:?}"
    );
    assert!(lines[1].contains("process 'sensor-2' (from the template at FILE:8, i = 2)"));
    // Two repetitions with one name is the duplicate-name error.
    let lines = errors(
        &TEMPLATED.replace("name = \"sensor-{i}\"", "name = \"sensor\""),
        &["args.n=3"],
    );
    assert_eq!(
        lines,
        [
            "FILE:9: process 'sensor' (from the template at FILE:8, i = 2), key 'name': 'sensor' is already the name of an earlier process (line 9)"
        ]
    );
}
