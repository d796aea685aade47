//! A launcher held off the CPU (a loaded machine, a debugger, a VM migrating) for longer than
//! the old 1 s lease: the group goes on with the default `group.host_lease`.

use caravan_tests::hosts::{Hosts, Launcher, pid_of};
use caravan_tests::{Scenario, caravan, wait_until};

/// The shipped three-host convoy in lockstep; the clock host's launcher (the hub the others
/// dial) is stopped for 1.5 s mid-run. Every host completes, and the recording has the bytes
/// of the same file run on one machine.
#[test]
fn a_three_host_lockstep_convoy_survives_a_launcher_paused_for_one_and_a_half_seconds() {
    let names = ["world", "pc", "robots"];
    let hosts = Hosts::new("pause", &names);
    let s = Scenario::new("hosts-pause", "");
    let file = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../launch/convoy/convoy-hosts.toml"
    );
    let hub = hosts
        .endpoint("world")
        .trim_start_matches("tcp/")
        .to_string();
    let sets = [
        format!("group.name={}", s.group.name),
        "group.duration=3s".to_string(),
        format!("args.hub={hub}"),
    ];
    let mut extra = Vec::new();
    for set in &sets {
        extra.extend(["--set", set.as_str()]);
    }
    // One machine first, with the arguments the clock host's launcher gets but --host.
    let runs = s.dir.join("runs-world");
    let mut args = vec![
        "launch",
        file,
        "--quiet",
        "--runs-dir",
        runs.to_str().unwrap(),
    ];
    args.extend(&extra);
    let out = caravan(&args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let one_dir = hosts.run_dir("world", &s.dir);
    let one = std::fs::read(one_dir.join("record.mcap")).unwrap();
    std::fs::remove_dir_all(one_dir).unwrap();

    let launchers: Vec<(&str, Launcher)> = names
        .into_iter()
        .map(|h| {
            let l = Launcher::start_file(&hosts, h, file.as_ref(), &s.dir, &extra);
            (h, l)
        })
        .collect();
    wait_until("every host runs its part", || {
        launchers
            .iter()
            .all(|(_, l)| l.stderr().contains("run directory"))
    });
    let world = pid_of(&s, "world");
    assert!(
        !launchers[0].1.stderr().contains("completed"),
        "too late to pause"
    );
    unsafe { libc::kill(world, libc::SIGSTOP) };
    std::thread::sleep(std::time::Duration::from_millis(1500));
    unsafe { libc::kill(world, libc::SIGCONT) };
    let ended: Vec<_> = launchers
        .into_iter()
        .map(|(h, l)| (h, l.finish()))
        .collect();
    for (host, (code, err)) in &ended {
        assert_eq!(
            *code,
            Some(0),
            "host {host} ({:?}): {ended:#?}",
            hosts.how()
        );
        assert!(!err.contains("left the group"), "host {host}: {err}");
    }
    let many = std::fs::read(hosts.run_dir("world", &s.dir).join("record.mcap")).unwrap();
    assert!(
        one == many,
        "the paused run's recording differs from one machine's ({:?})",
        hosts.how()
    );
}
