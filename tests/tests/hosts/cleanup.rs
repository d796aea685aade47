//! A test run removes what an earlier, killed run of the host tests left on the machine.

use caravan_tests::hosts::remove_stale_namespaces;
use std::process::Command;

fn namespaces() -> String {
    let out = Command::new("ip").args(["netns", "list"]).output().unwrap();
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// A namespace named for a test process that is gone, with a launcher-like process still in
/// it (as nextest's time limit leaves them), is removed and its process killed; one of a live
/// test process is kept.
#[test]
fn the_namespaces_of_a_killed_test_run_are_removed_by_the_next() {
    let mut gone = Command::new("true").spawn().unwrap();
    let dead = gone.id();
    gone.wait().unwrap();
    let stale = format!("cv{dead}-kill-0");
    let live = format!("cv{}-live-0", std::process::id());
    for ns in [&stale, &live] {
        let made = Command::new("ip").args(["netns", "add", ns]).status();
        if !made.is_ok_and(|s| s.success()) {
            eprintln!("cannot make network namespaces here: nothing to clean");
            return;
        }
    }
    let mut left = Command::new("ip")
        .args(["netns", "exec", &stale, "sleep", "600"])
        .spawn()
        .unwrap();
    caravan_tests::wait_until("the sleeper runs in the stale namespace", || {
        let out = Command::new("ip").args(["netns", "pids", &stale]).output();
        out.is_ok_and(|o| !o.stdout.is_empty())
    });
    remove_stale_namespaces();
    let list = namespaces();
    Command::new("ip")
        .args(["netns", "del", &live])
        .status()
        .ok();
    assert!(!list.contains(&stale), "{list}");
    assert!(list.contains(&live), "{list}");
    let status = left.wait().unwrap();
    assert!(!status.success(), "the process left in it was not killed");
}
