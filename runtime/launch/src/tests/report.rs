//! `[[report]]` entries: executables that compute report sections after the run.

use super::*;

const REPORTS: &str = r#"[args]
world = "lab"

[group]
name = "g"

[[process]]
name = "p"
exec = "sleep"

[[report]]
exec = "caravan-physics"
params = { world = "worlds/$(arg world).toml", urdf = "robots/bot.urdf" }

[[report]]
exec = "planner --summary"
"#;

#[test]
fn launch_report_entries() {
    let lf = load_text(REPORTS, &["report.1.params.x=1"]).unwrap();
    assert_eq!(lf.reports.len(), 2);
    let r = &lf.reports[0];
    assert_eq!(r.exec, Exec::Workspace("caravan-physics".into()));
    assert_eq!(
        r.params,
        serde_json::json!({"world": "worlds/lab.toml", "urdf": "robots/bot.urdf"})
    );
    assert!(r.launch_dir.is_absolute());
    assert_eq!(
        lf.reports[1].exec,
        Exec::Command(vec!["planner".into(), "--summary".into()])
    );
    assert_eq!(lf.reports[1].params, serde_json::json!({"x": 1}));
    assert!(load_text(BASE, &[]).unwrap().reports.is_empty());
}

#[test]
fn launch_report_bad_entries_are_named() {
    let lines = errors(&REPORTS.replace("\"planner --summary\"", "\"plannr\""), &[]);
    assert_eq!(
        lines,
        [
            "FILE:16: report #2, key 'exec': unknown executable 'plannr': not a workspace binary and not on PATH"
        ]
    );
    let lines = errors(&REPORTS.replace("params = {", "parms = {"), &[]);
    assert_eq!(
        lines,
        ["FILE:13: report #1, key 'parms': unknown key; did you mean 'params'?"]
    );
    let lines = errors(
        &REPORTS.replace("exec = \"planner --summary\"", "params = {}"),
        &[],
    );
    assert_eq!(lines, ["FILE:15: report #2: missing required key 'exec'"]);
    let lines = errors(REPORTS, &["report.2.params.x=1"]);
    assert_eq!(
        lines,
        ["--set report.2.params.x=1: there are only 2 entries, numbered from 0"]
    );
}

#[test]
fn launch_report_entries_from_an_included_file_come_first() {
    let dir = write_files(&[
        (
            "top.toml",
            &format!("[[include]]\nfile = \"sub/r.toml\"\n{REPORTS}"),
        ),
        ("sub/r.toml", "[[report]]\nexec = \"sleep\"\n"),
    ]);
    let lf = load_in(&dir, "top.toml", &[]).unwrap();
    assert_eq!(lf.reports.len(), 3);
    assert_eq!(lf.reports[0].exec, Exec::Workspace("sleep".into()));
    assert_eq!(
        lf.reports[0].launch_dir,
        std::path::absolute(dir.join("sub")).unwrap()
    );
}
