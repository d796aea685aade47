//! ROS 2 on one machine for the tests: a private network for DDS, and the Cyclone DDS probe
//! (`tests/python/ros2_probe.py`), an independent ROS 2 endpoint to check the bridge with.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A DDS domain id of this test process's own (ROS 2 allows 0–232), so that two test runs on
/// one network never meet.
pub fn domain() -> u16 {
    120 + (std::process::id() % 100) as u16
}

/// The Python of `.venv-ros2` (Cyclone DDS and rosbags from the package registry), made on
/// first use as a Python agent's environment is.
pub fn ros2_python() -> PathBuf {
    let root = crate::workspace_root();
    let out = Command::new(root.join("python/caravan-python"))
        .args([
            "--venv",
            "ros2",
            "--requirements",
            "../tests/requirements-ros2.txt",
            "--setup",
        ])
        .output()
        .expect("run python/caravan-python");
    assert!(
        out.status.success(),
        "cannot make .venv-ros2: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    root.join(".venv-ros2/bin/python")
}

/// The probe's command line: `.venv-ros2`'s Python, the script, `args`.
pub fn probe(args: &[&str]) -> Vec<String> {
    let script = crate::workspace_root().join("tests/python/ros2_probe.py");
    let mut all = vec![
        ros2_python().display().to_string(),
        script.display().to_string(),
    ];
    all.extend(args.iter().map(|a| a.to_string()));
    all
}

/// Runs `main` in a network namespace of its own with only a loopback interface (multicast
/// on), made for this call (a user namespace too, so no privileges are needed) and gone when
/// its processes end; each of `companions` is started first in the same namespace, its
/// standard output written to `dir/companion-<k>.out` (and its errors to `….err`), waited
/// for until it prints `ros2_probe: ready` (at most two minutes), and stopped (SIGTERM) when
/// `main` ends. Returns `main`'s output.
pub fn in_private_network(dir: &Path, companions: &[Vec<String>], main: &[String]) -> Output {
    let quote = |words: &[String]| -> String {
        words
            .iter()
            .map(|w| {
                shlex::try_quote(w)
                    .expect("no NUL in an argument")
                    .into_owned()
            })
            .collect::<Vec<_>>()
            .join(" ")
    };
    let mut script = String::from(
        "ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo \
         || { echo 'cannot set up the private network' >&2; exit 97; }\n",
    );
    for (k, c) in companions.iter().enumerate() {
        let out = dir.join(format!("companion-{k}"));
        let out = shlex::try_quote(out.to_str().unwrap())
            .unwrap()
            .into_owned();
        script.push_str(&format!(
            "{} >{out}.out 2>{out}.err &\npids=\"$pids $!\"\n\
             n=0; until grep -q 'ros2_probe: ready' {out}.err || [ $n -ge 1200 ]; do \
             sleep 0.1; n=$((n+1)); done\n",
            quote(c)
        ));
    }
    script.push_str(&format!(
        "{}\nrc=$?\nkill $pids 2>/dev/null\nwait\nexit $rc\n",
        quote(main)
    ));
    Command::new("unshare")
        .args(["--user", "--map-root-user", "--net", "sh", "-c", &script])
        .output()
        .expect("run unshare")
}

/// The JSON lines a companion printed.
pub fn companion_lines(dir: &Path, k: usize) -> Vec<serde_json::Value> {
    let text = std::fs::read_to_string(dir.join(format!("companion-{k}.out"))).unwrap_or_default();
    text.lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect()
}
