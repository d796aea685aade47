//! The Slurm fixture (`caravan_tests::slurm::Cluster`) against real Slurm daemons: a job
//! array runs every task with its array variables and each task is reported COMPLETED; a job
//! whose script fails is reported FAILED; dropping the cluster ends its daemons and the jobs
//! still running. The first run installs Slurm (see `.config/nextest.toml`).

#[path = "slurm/sweep.rs"]
mod sweep;

use caravan_tests::slurm::Cluster;
use caravan_tests::{alive, wait_until};
use std::time::Duration;

/// Writes `script` (a shell script) into the cluster's folder and submits it with `args`.
fn submit(cluster: &Cluster, file: &str, script: &str, args: &[&str]) -> String {
    let path = cluster.dir.join(file);
    std::fs::write(&path, format!("#!/bin/sh\n{script}")).unwrap();
    let out = cluster.dir.join("slurm-%A_%a.out").display().to_string();
    let chdir = cluster.dir.display().to_string();
    let path = path.display().to_string();
    let id = cluster.submit(&[args, &["--output", &out, "--chdir", &chdir, &path]].concat());
    assert!(
        !id.is_empty() && id.bytes().all(|b| b.is_ascii_digit()),
        "sbatch printed no job id: {id:?}"
    );
    id
}

#[test]
fn array_tasks_see_their_index_and_complete() {
    let cluster = Cluster::start("array");
    let results = cluster.dir.join("results");
    std::fs::create_dir(&results).unwrap();
    let script = format!(
        "echo \"$SLURM_ARRAY_TASK_ID $SLURM_ARRAY_TASK_COUNT $SLURM_ARRAY_TASK_MIN\" \
         > '{}/task-'$SLURM_ARRAY_TASK_ID\n",
        results.display()
    );
    let id = submit(&cluster, "array.sh", &script, &["--array=1-3"]);
    let states = cluster.wait_for_job(&id, Duration::from_secs(60));
    let expected: Vec<(String, String)> = (1..=3)
        .map(|k| (k.to_string(), "COMPLETED".to_string()))
        .collect();
    assert_eq!(states, expected, "{}", cluster.logs());
    let mut files: Vec<String> = std::fs::read_dir(&results)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    assert_eq!(files, ["task-1", "task-2", "task-3"]);
    for k in 1..=3 {
        let text = std::fs::read_to_string(results.join(format!("task-{k}"))).unwrap();
        assert_eq!(text, format!("{k} 3 1\n"), "task {k}");
    }
}

#[test]
fn a_failing_job_is_reported_failed() {
    let cluster = Cluster::start("failing");
    let id = submit(&cluster, "fail.sh", "exit 3\n", &[]);
    let states = cluster.wait_for_job(&id, Duration::from_secs(60));
    assert_eq!(
        states,
        [(id.clone(), "FAILED".to_string())],
        "{}",
        cluster.logs()
    );
}

#[test]
fn dropping_the_cluster_ends_its_daemons_and_jobs() {
    let cluster = Cluster::start("drop");
    let pids = cluster.dir.join("job.pids");
    // The job's shell and its `sleep`, which slurmstepd (no child of slurmd's) watches over.
    let script = format!("sleep 600 &\necho \"$$ $!\" > '{}'\nwait\n", pids.display());
    submit(&cluster, "long.sh", &script, &[]);
    wait_until("the job runs", || {
        std::fs::read_to_string(&pids).is_ok_and(|s| s.ends_with('\n'))
    });
    let mut all: Vec<i32> = std::fs::read_to_string(&pids)
        .unwrap()
        .split_whitespace()
        .map(|p| p.parse().unwrap())
        .collect();
    let stat = std::fs::read_to_string(format!("/proc/{}/stat", all[0])).unwrap();
    let stepd = stat.rsplit(')').next().unwrap().split_whitespace().nth(1);
    all.push(stepd.unwrap().parse().unwrap());
    for daemon in ["munged", "slurmctld", "slurmd"] {
        let pid = std::fs::read_to_string(cluster.dir.join(format!("{daemon}.pid"))).unwrap();
        all.push(pid.trim().parse().unwrap());
    }
    assert!(all.iter().all(|&p| alive(p)), "{all:?}");
    let dir = cluster.dir.clone();
    drop(cluster);
    let left: Vec<i32> = all.into_iter().filter(|&p| alive(p)).collect();
    assert!(left.is_empty(), "still running: {left:?}");
    assert!(!dir.exists(), "{} is left", dir.display());
}
