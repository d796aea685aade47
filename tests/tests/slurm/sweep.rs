//! `caravan sweep --slurm` on a real one-node Slurm cluster: the job array's shards, merged,
//! give the summary of the same sweep run locally, and submitting again reruns only what did
//! not finish.

use caravan_tests::slurm::Cluster;
use caravan_tests::sweep::{TempDir, comparable, lockstep_pingpong, read_json};
use caravan_tests::workspace_bin;
use std::path::Path;
use std::process::{Command, Output};
use std::time::Duration;

fn caravan(cluster: &Cluster, args: &[String], extra: &[&str]) -> Output {
    Command::new(workspace_bin("caravan"))
        .args(args)
        .args(extra)
        .envs(cluster.envs())
        .output()
        .unwrap()
}

fn text(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// The tasks' own output (`OUT/slurm/<job>_<task>.out`), for failure messages.
fn task_logs(out: &Path) -> String {
    let mut logs = String::new();
    for entry in std::fs::read_dir(out.join("slurm")).into_iter().flatten() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|x| x == "out") {
            let body = std::fs::read_to_string(&path).unwrap_or_default();
            logs += &format!("--- {}\n{body}", path.display());
        }
    }
    logs
}

/// Submits the sweep with `--slurm`, waits for its job and checks every task completed.
fn submit_and_wait(cluster: &Cluster, sweep: &[String], out: &Path, expect_tasks: &[&str]) {
    let o = out.to_str().unwrap();
    let run = caravan(
        cluster,
        sweep,
        &["--out", o, "--shards", "2", "--slurm", "-c", "1"],
    );
    assert_eq!(run.status.code(), Some(0), "{}", text(&run));
    // What a user sees (with --no-capture).
    eprintln!("{}", text(&run));
    let id = String::from_utf8_lossy(&run.stdout).trim().to_string();
    assert!(
        !id.is_empty() && id.bytes().all(|b| b.is_ascii_digit()),
        "no job id: {}",
        text(&run)
    );
    let states = cluster.wait_for_job(&id, Duration::from_secs(240));
    let expected: Vec<(String, String)> = (expect_tasks.iter())
        .map(|k| (k.to_string(), "COMPLETED".to_string()))
        .collect();
    assert_eq!(states, expected, "{}\n{}", task_logs(out), cluster.logs());
}

#[test]
fn a_sweep_submitted_to_slurm_and_merged_equals_the_local_sweep() {
    let cluster = Cluster::start("sweep");
    let tmp = TempDir::new("slurm-sweep");
    let mut sweep = vec!["sweep".to_string()];
    sweep.extend(lockstep_pingpong("1,3", "1..=2"));

    let local = tmp.0.join("local");
    let run = caravan(&cluster, &sweep, &["--out", local.to_str().unwrap()]);
    assert_eq!(run.status.code(), Some(0), "{}", text(&run));
    let expected = comparable(&read_json(&local.join("summary.json")));

    // 2 cells × 2 seeds in 2 shards: array tasks 1 and 2.
    let out = tmp.0.join("cluster");
    submit_and_wait(&cluster, &sweep, &out, &["1", "2"]);
    let merge = |dir: &Path| {
        let merge: Vec<String> = ["sweep", "merge", dir.to_str().unwrap()]
            .map(String::from)
            .to_vec();
        caravan(&cluster, &merge, &[])
    };
    let run = merge(&out);
    eprintln!("{}", text(&run));
    assert_eq!(run.status.code(), Some(0), "{}", text(&run));
    assert_eq!(comparable(&read_json(&out.join("summary.json"))), expected);

    // Everything finished: nothing is submitted.
    let o = out.to_str().unwrap();
    let run = caravan(&cluster, &sweep, &["--out", o, "--shards", "2", "--slurm"]);
    assert_eq!(run.status.code(), Some(0), "{}", text(&run));
    assert!(text(&run).contains("nothing to submit"), "{}", text(&run));
    assert!(String::from_utf8_lossy(&run.stdout).trim().is_empty());

    // A lost run (gain 3, seed 2: run 3 in the sweep's order, so shard 2) is all a
    // resubmission runs; the other runs stay as they were.
    let kept = out.join("runs/gain=1/seed-1");
    let before: Vec<_> = std::fs::read_dir(&kept)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    std::fs::remove_dir_all(out.join("runs/gain=3/seed-2")).unwrap();
    submit_and_wait(&cluster, &sweep, &out, &["2"]);
    let script = std::fs::read_to_string(out.join("slurm/sweep.sbatch")).unwrap();
    assert!(script.contains("#SBATCH --array=2\n"), "{script}");
    let after: Vec<_> = std::fs::read_dir(&kept)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(before, after);
    let run = merge(&out);
    assert_eq!(run.status.code(), Some(0), "{}", text(&run));
    assert_eq!(comparable(&read_json(&out.join("summary.json"))), expected);
}
