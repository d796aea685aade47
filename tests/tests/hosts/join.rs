//! A launcher stopped while it waits for the other hosts to join: by a signal it can handle,
//! it removes its group's lock and config; killed, it leaves them for `caravan clean`.

use super::two_hosts;
use caravan_tests::{Scenario, caravan, wait_until};
use std::path::PathBuf;

/// The files a launcher of `s`'s group keeps in the temporary directory while it runs.
fn group_files(s: &Scenario) -> [PathBuf; 2] {
    let name = &s.group.name;
    let tmp = std::env::temp_dir();
    [
        tmp.join(format!("caravan-group-{name}.lock")),
        tmp.join(format!("caravan-group-{name}.iceoryx2.toml")),
    ]
}

/// Starts host a of a group whose host b never comes, and returns once it waits for b (its
/// config is written after it starts watching for signals).
fn waiting_launcher(s: &Scenario) -> std::process::Child {
    let child = s
        .command(&["--host", "a"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    wait_until("the launcher holds its group's lock and config", || {
        group_files(s).iter().all(|f| f.exists())
    });
    child
}

/// SIGTERM, and Ctrl-C (SIGINT, which said "did not join within 60s" before).
#[test]
fn a_host_launcher_stopped_by_a_signal_while_it_waits_for_the_others_removes_its_lock() {
    for signal in [libc::SIGTERM, libc::SIGINT] {
        let s = Scenario::new("hosts-signal", &two_hosts("realtime", ""));
        let child = waiting_launcher(&s);
        // The group is taken while its launcher waits: not another's to clean.
        let out = caravan(&["clean", "--group", &s.group.name]);
        assert_eq!(out.status.code(), Some(2), "{:?}", out);
        // SAFETY: signalling the child this test started.
        unsafe { libc::kill(child.id() as i32, signal) };
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(128 + signal), "{err}");
        let said = format!("stopped by signal {signal} while waiting for the other hosts");
        assert!(err.contains(&said), "{err}");
        assert!(!err.contains("did not join"), "{err}");
        for f in group_files(&s) {
            assert!(!f.exists(), "{} left behind", f.display());
        }
        assert!(s.run_dirs().is_empty(), "a run directory was made: {err}");
        assert!(s.shm_entries().is_empty(), "{:?}", s.shm_entries());
    }
}

#[test]
fn caravan_clean_removes_the_lock_and_config_a_killed_host_launcher_left() {
    let s = Scenario::new("hosts-sigkill", &two_hosts("realtime", ""));
    let mut child = waiting_launcher(&s);
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(group_files(&s).iter().all(|f| f.exists()));
    let out = caravan(&["clean", "--group", &s.group.name]);
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{out:?}");
    assert!(said.contains("its lock and config"), "{said}");
    for f in group_files(&s) {
        assert!(!f.exists(), "{} left behind", f.display());
    }
    let out = caravan(&["clean", "--group", &s.group.name]);
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(said.contains("left nothing to clean"), "{said}");
}
