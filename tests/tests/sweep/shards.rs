//! Sharded sweeps: `--shard`, `caravan sweep merge`, and the Slurm script's dry run.

use caravan_tests::sweep::{TempDir, comparable, lockstep_pingpong, read_json};
use caravan_tests::workspace_bin;
use std::path::Path;
use std::process::{Command, Output};

fn caravan_sweep(args: &[String], extra: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(workspace_bin("caravan"));
    cmd.arg("sweep").args(args).args(extra);
    for var in [
        "SLURM_ARRAY_TASK_ID",
        "SLURM_ARRAY_TASK_COUNT",
        "JOB_COMPLETION_INDEX",
    ] {
        cmd.env_remove(var);
    }
    cmd.envs(env.iter().copied()).output().unwrap()
}

fn merge(out: &Path, dirs: &[&Path], extra: &[&str]) -> Output {
    Command::new(workspace_bin("caravan"))
        .args(["sweep", "merge"])
        .arg(out)
        .args(dirs)
        .args(extra)
        .output()
        .unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).to_string()
}

/// The run directories under `<out>/runs/<cell>/seed-<s>/`.
fn runs_in(out: &Path) -> usize {
    let mut n = 0;
    for cell in std::fs::read_dir(out.join("runs")).into_iter().flatten() {
        for seed in std::fs::read_dir(cell.unwrap().path()).unwrap() {
            n += std::fs::read_dir(seed.unwrap().path())
                .unwrap()
                .filter(|e| e.as_ref().unwrap().path().is_dir())
                .count();
        }
    }
    n
}

#[test]
fn a_sweep_split_three_ways_and_merged_equals_one_local_run() {
    let tmp = TempDir::new("sweep-shards");
    let args = lockstep_pingpong("1,3", "1..=3");
    let local = tmp.0.join("local");
    let run = caravan_sweep(&args, &["--out", local.to_str().unwrap()], &[]);
    assert_eq!(run.status.code(), Some(0), "{}", stderr(&run));

    // Shard 1 by number, 2 as a Slurm array task, 3 as a Kubernetes Indexed Job's pod.
    let dirs: Vec<_> = (1..=3).map(|k| tmp.0.join(format!("shard-{k}"))).collect();
    let ways: [(&str, &[(&str, &str)]); 3] = [
        ("1/3", &[]),
        (
            "env",
            &[
                ("SLURM_ARRAY_TASK_ID", "2"),
                ("SLURM_ARRAY_TASK_COUNT", "3"),
            ],
        ),
        ("env/3", &[("JOB_COMPLETION_INDEX", "2")]),
    ];
    for (k, (shard, env)) in ways.iter().enumerate() {
        let out = dirs[k].to_str().unwrap();
        let run = caravan_sweep(&args, &["--out", out, "--shard", shard], env);
        assert_eq!(run.status.code(), Some(0), "{}", stderr(&run));
        assert!(
            dirs[k]
                .join(format!("shards/{}-of-3.json", k + 1))
                .is_file(),
            "{}",
            stderr(&run)
        );
        assert_eq!(runs_in(&dirs[k]), 2, "shard {}: {}", k + 1, stderr(&run));
        // A shard's summary would be a part of the sweep's: only the merge writes one.
        assert!(!dirs[k].join("summary.json").exists());
    }

    let merged = tmp.0.join("merged");
    let refs: Vec<&Path> = dirs.iter().map(|d| d.as_path()).collect();
    let run = merge(&merged, &refs, &[]);
    assert_eq!(run.status.code(), Some(0), "{}", stderr(&run));
    let (local_summary, merged_summary) = (
        read_json(&local.join("summary.json")),
        read_json(&merged.join("summary.json")),
    );
    assert_eq!(comparable(&merged_summary), comparable(&local_summary));
    // Every run's directory is found from the merged summary's folder.
    for cell in merged_summary["cells"].as_array().unwrap() {
        for r in cell["runs"].as_array().unwrap() {
            let dir = merged.join(r["dir"].as_str().unwrap());
            assert!(dir.join("report.json").is_file(), "{}", dir.display());
        }
    }
    let csv = std::fs::read_to_string(merged.join("summary.csv")).unwrap();
    assert!(csv.contains("gain=3,nodes.pong.steps,number,3,"), "{csv}");

    // A missing shard is named, and nothing is written unless asked.
    let partial = tmp.0.join("partial");
    let run = merge(&partial, &refs[..2], &[]);
    assert_eq!(run.status.code(), Some(2), "{}", stderr(&run));
    assert!(
        stderr(&run).contains("shard 3/3 has no manifest in any directory"),
        "{}",
        stderr(&run)
    );
    assert!(stderr(&run).contains("2 runs missing"), "{}", stderr(&run));
    assert!(!partial.join("summary.json").exists());
    let run = merge(&partial, &refs[..2], &["--allow-missing"]);
    assert_eq!(run.status.code(), Some(0), "{}", stderr(&run));
    assert!(
        stderr(&run).contains("warning: shard 3/3"),
        "{}",
        stderr(&run)
    );
    let summary = read_json(&partial.join("summary.json"));
    let n: u64 = (summary["cells"].as_array().unwrap().iter())
        .map(|c| c["metrics"]["nodes.pong.steps"]["n"].as_u64().unwrap())
        .sum();
    assert_eq!(n, 4);

    // The job array of shard 1's folder holds only the shards with unfinished runs.
    let out = dirs[0].to_str().unwrap();
    let run = caravan_sweep(
        &args,
        &[
            "--out",
            out,
            "--shards",
            "3",
            "--slurm",
            "--time=5",
            "--dry-run",
        ],
        &[],
    );
    assert_eq!(run.status.code(), Some(0), "{}", stderr(&run));
    let script = std::fs::read_to_string(dirs[0].join("slurm/sweep.sbatch")).unwrap();
    assert!(script.contains("#SBATCH --array=2-3\n"), "{script}");
    assert!(script.contains("#SBATCH --time=5\n"), "{script}");
    assert!(
        script.contains("--shard \"$SLURM_ARRAY_TASK_ID/3\"\n"),
        "{script}"
    );
}

#[test]
fn shards_of_another_sweep_are_refused() {
    let tmp = TempDir::new("sweep-other");
    let (a, b) = (tmp.0.join("a"), tmp.0.join("b"));
    let args = lockstep_pingpong("1,3", "1");
    let run = caravan_sweep(
        &args,
        &["--out", a.to_str().unwrap(), "--shard", "1/2"],
        &[],
    );
    assert_eq!(run.status.code(), Some(0), "{}", stderr(&run));
    let other = lockstep_pingpong("1,5", "1");
    let run = caravan_sweep(
        &other,
        &["--out", b.to_str().unwrap(), "--shard", "2/2"],
        &[],
    );
    assert_eq!(run.status.code(), Some(0), "{}", stderr(&run));
    let merged = tmp.0.join("merged");
    let run = merge(&merged, &[&a, &b], &[]);
    assert_eq!(run.status.code(), Some(2), "{}", stderr(&run));
    let err = stderr(&run);
    assert!(err.contains("is a shard of another sweep"), "{err}");
    assert!(
        err.contains("axes [process.pong.params.gain=1,3] against [process.pong.params.gain=1,5]"),
        "{err}"
    );
    assert!(!merged.join("summary.json").exists());
    // A folder that is no sweep's output is named.
    let run = merge(&merged, &[&tmp.0], &[]);
    assert_eq!(run.status.code(), Some(2), "{}", stderr(&run));
    assert!(
        stderr(&run).contains("no shard manifests"),
        "{}",
        stderr(&run)
    );
}

#[test]
fn bad_shards_start_nothing() {
    let tmp = TempDir::new("sweep-badshard");
    let out = tmp.0.join("out");
    let args = lockstep_pingpong("1,3", "1..=3");
    let o = out.to_str().unwrap();
    // Extra arguments, environment, and what the message must say.
    type Case<'a> = (&'a [&'a str], &'a [(&'a str, &'a str)], &'a str);
    let cases: [Case; 5] = [
        (&["--shard", "4/3"], &[], "shard 4 of 3 does not exist"),
        (&["--shard", "1/0"], &[], "1 to 1000"),
        (
            &["--shard", "env"],
            &[],
            "SLURM_ARRAY_TASK_COUNT is not set",
        ),
        (
            &["--shard", "env"],
            &[
                ("SLURM_ARRAY_TASK_ID", "0"),
                ("SLURM_ARRAY_TASK_COUNT", "2"),
            ],
            "--array=1-2",
        ),
        (
            &["--slurm", "--seeds", "1"],
            &[],
            "put Caravan's --seeds before --slurm",
        ),
    ];
    for (extra, env, expected) in cases {
        let mut all = vec!["--out", o];
        all.extend(extra);
        let run = caravan_sweep(&args, &all, env);
        assert_eq!(run.status.code(), Some(2), "{extra:?}: {}", stderr(&run));
        assert!(
            stderr(&run).contains(expected),
            "{extra:?}: {}",
            stderr(&run)
        );
        assert!(!out.exists(), "{extra:?} created {}", out.display());
    }
}
