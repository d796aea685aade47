//! The edges of `caravan.report`'s protocol, run as the launcher runs a plugin but without a
//! group: arguments, params that are not JSON, a run directory without `run.json`, a section
//! holding NaN, and section names or Markdown the launcher would not merge.

use caravan_tests::{python_env, workspace_root};
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

/// A plugin whose params say what to write: `value` into section `name`, `markdown` as its
/// Markdown, or fail with `raise`.
const PLUGIN: &str = r###"
from caravan import report

@report.plugin("edge-report", params={"name": "edge", "markdown": "## Edge\n", "raise": ""})
def edge(run, p):
    if p["raise"]:
        raise RuntimeError(p["raise"])
    value = {"nan": float("nan"), "inf": [float("inf"), 1.5], "outcome": run.facts["outcome"]}
    return [report.Section(p["name"], value, p["markdown"])]

if __name__ == "__main__":
    edge.main()
"###;

fn run(dir: &Path, args: &[&str], params: &str) -> Output {
    Command::new(python_env())
        .arg(dir.join("edge.py"))
        .args(args)
        .env("PYTHONPATH", workspace_root().join("python"))
        .env("CARAVAN_PARAMS", params)
        .env("CARAVAN_LAUNCH_DIR", dir)
        .output()
        .unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn a_python_plugin_follows_the_protocol_at_its_edges() {
    let dir = std::env::temp_dir().join(format!("caravan-py-edge-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let run_dir = dir.join("run");
    std::fs::create_dir_all(&run_dir).unwrap();
    std::fs::write(dir.join("edge.py"), PLUGIN).unwrap();
    let code = |out: &Output| out.status.code();

    // Arguments other than `--check` or one run directory: the usage, exit 2.
    for args in [&[][..], &["a", "b"], &["--verbose"]] {
        let out = run(&dir, args, "{}");
        assert_eq!(code(&out), Some(2), "{args:?}: {}", stderr(&out));
        assert!(stderr(&out).contains("usage: edge-report --check | edge-report RUN_DIR"));
    }
    let out = run(&dir, &["--check"], "{not json");
    assert_eq!(code(&out), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).starts_with("edge-report: CARAVAN_PARAMS is not JSON"));
    let out = run(&dir, &["--check"], "{}");
    assert_eq!(code(&out), Some(0), "{}", stderr(&out));
    assert!(
        !run_dir.join("sections").exists(),
        "--check wrote something"
    );

    // No run.json: a failure while computing (exit 1), naming the file.
    let out = run(&dir, &[run_dir.to_str().unwrap()], "{}");
    assert_eq!(code(&out), Some(1), "{}", stderr(&out));
    assert!(stderr(&out).contains("run.json"), "{}", stderr(&out));

    // NaN and infinities are written as null, as serde_json writes them, so the launcher reads
    // the section; the text is pretty-printed JSON ending in a newline.
    std::fs::write(run_dir.join("run.json"), r#"{"outcome": "completed"}"#).unwrap();
    let out = run(&dir, &[run_dir.to_str().unwrap()], "{}");
    assert_eq!(code(&out), Some(0), "{}", stderr(&out));
    let text = std::fs::read_to_string(run_dir.join("sections/edge.json")).unwrap();
    assert!(text.ends_with("}\n"), "{text}");
    let value: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(
        value,
        serde_json::json!({"nan": null, "inf": [null, 1.5], "outcome": "completed"})
    );
    let md = std::fs::read_to_string(run_dir.join("sections/edge.md")).unwrap();
    assert_eq!(md, "## Edge\n");

    // What the launcher would refuse or misplace is a failure naming it; so is an exception.
    for (params, expected) in [
        (
            r#"{"name": "Edge"}"#,
            "section name 'Edge' must be lower case letters, digits and '_'",
        ),
        (
            r#"{"name": "topics"}"#,
            "section name 'topics' is the generic report's own",
        ),
        (
            r#"{"markdown": "Edge\n"}"#,
            "its Markdown must start with a '## ' heading",
        ),
        (
            r#"{"raise": "no poses"}"#,
            "RuntimeError: no poses (edge.py:",
        ),
    ] {
        let out = run(&dir, &[run_dir.to_str().unwrap()], params);
        assert_eq!(code(&out), Some(1), "{params}: {}", stderr(&out));
        assert!(
            stderr(&out).contains(expected),
            "{params}: {}",
            stderr(&out)
        );
        assert_eq!(
            stderr(&out).lines().count(),
            1,
            "one line: {}",
            stderr(&out)
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
