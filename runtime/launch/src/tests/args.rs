//! Arguments that use other arguments.

use super::*;

const ARGS: &str = r#"[args]
world_file = "worlds/$(arg world).toml"
world = "lab"
a = "$(arg b)"
b = "$(arg a)"

[group]
name = "g"

[[process]]
name = "p"
exec = "sleep"
params = { world = "$(arg world_file)", both = ["$(arg world)", "$(arg world_file)"] }
"#;

fn valid() -> String {
    ARGS.replace("a = \"$(arg b)\"\nb = \"$(arg a)\"\n", "")
}

#[test]
fn launch_args_use_args() {
    let lf = load_text(&valid(), &[]).unwrap();
    assert_eq!(
        lf.processes[0].params,
        serde_json::json!({"world": "worlds/lab.toml", "both": ["lab", "worlds/lab.toml"]})
    );
    assert!(
        lf.resolved_toml
            .contains("world_file = \"worlds/lab.toml\"")
    );
    // Resolved after --set args.*, which may use arguments too.
    let lf = load_text(&valid(), &["args.world=hall"]).unwrap();
    assert_eq!(lf.processes[0].params["world"], "worlds/hall.toml");
    let lf = load_text(
        &valid(),
        &["args.world=$(arg world_file)x", "args.world_file=w"],
    )
    .unwrap();
    assert_eq!(
        lf.processes[0].params["both"],
        serde_json::json!(["wx", "w"])
    );
    // A command-line value may use arguments.
    let lf = load_text(&valid(), &["process.p.params.k=$(arg world)"]).unwrap();
    assert_eq!(lf.processes[0].params["k"], "lab");
}

#[test]
fn launch_args_cycles_and_unknown_names() {
    let lines = errors(
        &ARGS.replace("params = {", "params = { x = \"$(arg a)\","),
        &[],
    );
    // Once, where the cycle closes; the process using it says nothing more.
    assert_eq!(
        lines,
        ["FILE:5: arguments refer to each other in a cycle: a → b → a"]
    );
    let lines = errors(&valid().replace("\"lab\"", "\"$(arg wrld)\""), &[]);
    assert_eq!(
        lines,
        ["FILE:3: '$(arg wrld)' names no argument in [args]; did you mean 'world'?"]
    );
    let lines = errors(&valid(), &["args.world=$(arg world_file)"]);
    assert_eq!(
        lines,
        [
            "--set args.world=$(arg world_file): arguments refer to each other in a cycle: world_file → world → world_file"
        ]
    );
    let lines = errors(&valid(), &["process.p.params.k=$(arg nope)"]);
    assert_eq!(
        lines,
        ["--set process.p.params.k=$(arg nope): '$(arg nope)' names no argument in [args]"]
    );
}
