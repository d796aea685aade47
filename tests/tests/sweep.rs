//! `caravan sweep`: a grid of real pingpong groups, resumption, and bad input.

use caravan_tests::sweep::{TempDir, read_json, sweep};
use caravan_tests::workspace_root;
use std::path::{Path, PathBuf};
use std::process::Output;

#[path = "sweep/shards.rs"]
mod shards;

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).to_string()
}

/// Every run directory: `<out>/runs/<cell>/seed-<s>/<group>-<time>`.
fn run_dirs(out: &Path) -> Vec<PathBuf> {
    let mut dirs = Vec::new();
    for cell in std::fs::read_dir(out.join("runs")).into_iter().flatten() {
        for seed in std::fs::read_dir(cell.unwrap().path()).unwrap() {
            for run in std::fs::read_dir(seed.unwrap().path()).unwrap() {
                let run = run.unwrap().path();
                if run.is_dir() {
                    dirs.push(run);
                }
            }
        }
    }
    dirs.sort();
    dirs
}

/// No shared memory of any group the sweep ran is left.
fn assert_no_resources(dirs: &[PathBuf]) {
    let left = caravan::group::groups_with_resources();
    for dir in dirs {
        let report = read_json(&dir.join("report.json"));
        let group = report["group"]["name"].as_str().unwrap();
        assert!(
            !left.iter().any(|g| g == group),
            "{group} left shared memory"
        );
    }
}

#[test]
fn a_grid_of_pingpong_groups_is_summarised_and_resumed() {
    let tmp = TempDir::new("sweep");
    let out = tmp.0.join("out");
    let launch = workspace_root().join("launch/pingpong.toml");
    let args = [
        launch.to_str().unwrap(),
        "--grid",
        "process.pong.params.gain=1,3",
        "--seeds",
        "1..=2",
        "--jobs",
        "2",
        "--duration",
        "3s",
    ];
    let first = sweep(&args, &out);
    assert_eq!(first.status.code(), Some(0), "{}", stderr(&first));
    let dirs = run_dirs(&out);
    assert_eq!(dirs.len(), 4, "{dirs:?}");
    assert_no_resources(&dirs);

    let summary = read_json(&out.join("summary.json"));
    assert_eq!(summary["name"], "pingpong");
    assert_eq!(summary["seeds"], serde_json::json!([1, 2]));
    assert_eq!(summary["axes"][0]["key"], "process.pong.params.gain");
    let cells = summary["cells"].as_array().unwrap();
    assert_eq!(cells.len(), 2);
    // Values keep the type they have as `--set` values: the gains are numbers.
    assert_eq!(summary["axes"][0]["values"], serde_json::json!([1, 3]));
    for (cell, gain) in cells.iter().zip([1, 3]) {
        assert_eq!(cell["values"]["process.pong.params.gain"], gain);
        assert_eq!(cell["sets"]["process.pong.params.gain"], gain);
        assert_eq!(cell["runs"].as_array().unwrap().len(), 2);
        for run in cell["runs"].as_array().unwrap() {
            assert_eq!(run["exit_code"], 0);
            assert_eq!(run["outcome"], "completed");
            assert!(
                out.join(run["dir"].as_str().unwrap())
                    .join("report.json")
                    .is_file()
            );
        }
        // 3 s at 10 Hz: pong steps once per ping but the last.
        let steps = &cell["metrics"]["nodes.pong.steps"];
        assert_eq!(steps["n"], 2, "{cell}");
        assert_eq!(steps["mean"], 30.0, "{cell}");
        assert_eq!(steps["sd"], 0.0, "{cell}");
        assert_eq!(cell["metrics"]["topics.demo/ping.messages"]["n"], 2);
        let completed = &cell["flags"]["run.completed"];
        assert_eq!(completed["n"], 2, "{cell}");
        assert_eq!(completed["rate"], 1.0, "{cell}");
    }
    let csv = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    assert!(
        csv.starts_with("process.pong.params.gain,cell,metric,kind,"),
        "{csv}"
    );
    assert!(csv.contains("\n3,gain=3,run.completed,flag,2,1,"), "{csv}");

    // Again: every run is already finished, so nothing runs and the summary is the same.
    let json_before = std::fs::read_to_string(out.join("summary.json")).unwrap();
    let again = sweep(&args, &out);
    assert_eq!(again.status.code(), Some(0), "{}", stderr(&again));
    assert!(
        stderr(&again).contains("skipped 4 of 4 runs"),
        "{}",
        stderr(&again)
    );
    assert_eq!(run_dirs(&out), dirs);
    let json_after = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert_eq!(json_before, json_after);
}

#[test]
fn a_bad_grid_key_starts_nothing() {
    let tmp = TempDir::new("sweep-bad");
    let out = tmp.0.join("out");
    let launch = workspace_root().join("launch/pingpong.toml");
    let bad = sweep(
        &[
            launch.to_str().unwrap(),
            "--grid",
            "process.nope.rate=1Hz",
            "--duration",
            "3s",
        ],
        &out,
    );
    assert_eq!(bad.status.code(), Some(2), "{}", stderr(&bad));
    assert!(
        stderr(&bad).contains("process.nope.rate=1Hz"),
        "{}",
        stderr(&bad)
    );
    assert!(
        stderr(&bad).contains("no process 'nope'"),
        "{}",
        stderr(&bad)
    );
    assert!(!out.exists(), "a bad sweep created {}", out.display());
}

#[test]
fn sweep_files_bundle_overrides_and_report_bad_keys_with_lines() {
    let tmp = TempDir::new("sweep-file");
    let launch = workspace_root().join("launch/pingpong.toml");
    let file = tmp.0.join("demo.toml");
    std::fs::write(
        &file,
        format!(
            r#"[sweep]
name = "demo"
launch = "{}"
seeds = [5]
set = ["group.duration=2s"]

[[sweep.axis]]
name = "speed"
[sweep.axis.values]
slow = ["process.ping.rate=5Hz"]
fast = ["process.ping.rate=20Hz", "process.pong.params.gain=4"]
"#,
            launch.display()
        ),
    )
    .unwrap();
    let out = tmp.0.join("out");
    let good = sweep(&[file.to_str().unwrap()], &out);
    assert_eq!(good.status.code(), Some(0), "{}", stderr(&good));
    let summary = read_json(&out.join("summary.json"));
    assert_eq!(summary["name"], "demo");
    assert_eq!(summary["axes"][0]["name"], "speed");
    let cells = summary["cells"].as_array().unwrap();
    let ids: Vec<&str> = cells.iter().map(|c| c["id"].as_str().unwrap()).collect();
    assert_eq!(ids, ["speed=slow", "speed=fast"]);
    assert_eq!(cells[1]["sets"]["process.pong.params.gain"], 4);
    // 2 s: ping steps 11 times at 5 Hz, 41 times at 20 Hz.
    assert_eq!(cells[0]["metrics"]["nodes.ping.steps"]["mean"], 11.0);
    assert_eq!(cells[1]["metrics"]["nodes.ping.steps"]["mean"], 41.0);
    assert_eq!(cells[0]["runs"][0]["seed"], 5);
    assert_no_resources(&run_dirs(&out));

    let bad_file = tmp.0.join("bad.toml");
    std::fs::write(
        &bad_file,
        format!("[sweep]\nlaunch = \"{}\"\nseed = 3\n", launch.display()),
    )
    .unwrap();
    let bad_out = tmp.0.join("bad-out");
    let bad = sweep(&[bad_file.to_str().unwrap()], &bad_out);
    assert_eq!(bad.status.code(), Some(2), "{}", stderr(&bad));
    let expected = format!("{}:3: [sweep] key 'seed': unknown key", bad_file.display());
    assert!(stderr(&bad).contains(&expected), "{}", stderr(&bad));
    assert!(!bad_out.exists());

    // A value the launch file refuses is named by its --set and by the sweep file's line.
    let bad_value = tmp.0.join("bad-value.toml");
    std::fs::write(
        &bad_value,
        format!(
            "[sweep]\nlaunch = \"{}\"\n\n[[sweep.axis]]\nkey = \"process.ping.rate\"\nvalues = [\"10Hz\",\n  \"fast\"]\n\n[[sweep.axis]]\nname = \"gain\"\n[sweep.axis.values]\nlow = [\"process.pong.params.gain=1\"]\nnone = [\"process.pong.params.gain=none\"]\n",
            launch.display()
        ),
    )
    .unwrap();
    let out = sweep(&[bad_value.to_str().unwrap()], &tmp.0.join("bad-value-out"));
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let err = stderr(&out);
    let at = |line: usize| format!("({}:{line})", bad_value.display());
    assert!(
        err.contains(&format!("--set process.ping.rate=fast {}", at(7))),
        "{err}"
    );
    assert!(
        err.contains(&format!("--set process.pong.params.gain=none {}", at(13))),
        "{err}"
    );
}

/// A grid past the cell cap is refused at once; a big one says that it is checking its cells
/// (each is loaded as `caravan launch` would), so the sweep is never silent for long.
#[test]
fn a_huge_grid_is_refused_and_a_big_one_says_it_checks_its_cells() {
    let tmp = TempDir::new("sweep-huge");
    let out = tmp.0.join("out");
    let launch = workspace_root().join("launch/pingpong.toml");
    let ten = (1..=10)
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(",");
    let mut args = vec![launch.to_str().unwrap().to_string()];
    for axis in ["a", "b", "c", "d", "e", "f"] {
        args.extend(["--grid".into(), format!("process.pong.params.{axis}={ten}")]);
    }
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let huge = sweep(&refs, &out);
    assert_eq!(huge.status.code(), Some(2), "{}", stderr(&huge));
    assert!(
        stderr(&huge).contains(
            "the grid has 10 × 10 × 10 × 10 × 10 × 10 = 1000000 cells, more than the 100000 a \
             sweep takes; nothing was checked or run"
        ),
        "{}",
        stderr(&huge)
    );
    assert!(!out.exists());

    // 200 cells, every one with an unknown process: checked, with a progress line, refused.
    let many = (1..=200)
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(",");
    let grid = format!("process.pong.params.gain={many}");
    let run = std::process::Command::new(caravan_tests::workspace_bin("caravan"))
        .args(["sweep", launch.to_str().unwrap(), "--grid", &grid])
        .args(["--set", "process.nope.rate=1Hz", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2), "{}", stderr(&run));
    let err = stderr(&run);
    assert!(err.contains("checking 200 cells"), "{err}");
    assert!(err.contains("no process 'nope'"), "{err}");
    assert!(err.contains("(every cell)"), "{err}");
    assert!(!out.exists());
}

/// Every cell is checked as `caravan launch` would, but a process whose command, params and
/// environment no cell changes is checked once for the whole grid; a process the grid does
/// change is still checked in each cell, and a cell it refuses is named alone.
#[test]
fn a_sweep_checks_a_process_its_grid_does_not_change_once() {
    let tmp = TempDir::new("sweep-memo");
    let count = tmp.0.join("checks.txt");
    let script = tmp.0.join("count.sh");
    std::fs::write(
        &script,
        format!(
            "#!/bin/sh\n[ \"$CARAVAN_CHECK\" = 1 ] && echo checked >> '{}' && exit 0\nexec sleep 600\n",
            count.display()
        ),
    )
    .unwrap();
    std::fs::set_permissions(&script, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    let launch = tmp.0.join("launch.toml");
    std::fs::write(
        &launch,
        format!(
            "[group]\nname = \"memo\"\n{}\n[[process]]\nname = \"counter\"\nexec = \"./count.sh\"\nrate = \"1Hz\"\ncheck = true\n",
            caravan_tests::ping_pong()
        ),
    )
    .unwrap();
    let out = tmp.0.join("out");
    let run = sweep(
        &[
            launch.to_str().unwrap(),
            "--grid",
            "process.pong.params.gain=1,2,3,4,steep",
        ],
        &out,
    );
    assert_eq!(run.status.code(), Some(2), "{}", stderr(&run));
    let err = stderr(&run);
    assert!(err.contains("cell gain=steep: "), "{err}");
    assert!(err.contains("process 'pong'"), "{err}");
    assert_eq!(err.matches("process 'pong'").count(), 1, "{err}");
    let checks = std::fs::read_to_string(&count).unwrap();
    assert_eq!(checks.lines().count(), 1, "{checks}");
    assert!(!out.exists());
}
