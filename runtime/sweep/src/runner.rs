//! Runs the sweep's launches as child processes, `jobs` at a time: one worker thread per job
//! blocks in `wait` on its child, so nothing polls. Ctrl-C (SIGINT) or SIGTERM stops taking new
//! runs and forwards SIGTERM to the running launchers, which stop their groups cleanly (a second
//! signal is forwarded too: the launcher then kills its processes at once).

use anyhow::Result;
use crossbeam::channel::{Sender, unbounded};
use serde_json::Value;
use std::collections::HashSet;
use std::ffi::OsString;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

/// One launch to run.
#[derive(Debug, Clone)]
pub struct Task {
    pub cell: usize,
    pub seed: u64,
    /// The run's `--runs-dir`: `<out>/runs/<cell-id>/seed-<s>`.
    pub dir: PathBuf,
    pub group: String,
    /// Arguments after `caravan`.
    pub args: Vec<OsString>,
}

/// A launch that ended.
#[derive(Debug)]
pub struct Finished {
    pub cell: usize,
    pub seed: u64,
    /// The run directory the launcher created, if any.
    pub run_dir: Option<PathBuf>,
    /// `None` when killed by a signal or never started.
    pub exit_code: Option<i32>,
    pub report: Option<Value>,
    /// Stopped by the sweep's Ctrl-C before it finished: not a result.
    pub interrupted: bool,
    /// Why the launch could not be started, if it could not.
    pub error: Option<String>,
}

/// The finished run in a run's `--runs-dir`: a run directory whose `report.json` says it
/// completed, degraded or failed (an interrupted one is not finished).
pub fn finished_run(dir: &Path) -> Option<(PathBuf, Value)> {
    let (run_dir, report) = last_run(dir)?;
    let report = report?;
    matches!(
        report["run"]["outcome"].as_str(),
        Some("completed" | "degraded" | "failed")
    )
    .then_some((run_dir, report))
}

/// The newest run directory under `dir` and its report, if it has one.
fn last_run(dir: &Path) -> Option<(PathBuf, Option<Value>)> {
    let run_dir = caravan_report::latest_run_dir(dir)?;
    let report = std::fs::read_to_string(run_dir.join("report.json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok());
    Some((run_dir, report))
}

/// Children running now, by pid; `stopping` is set under the same lock so that no child is
/// started after the signal thread has sent its SIGTERMs.
#[derive(Default)]
struct Running {
    pids: HashSet<u32>,
    stopping: bool,
}

/// Runs `tasks` with `jobs` workers; `on_done` sees each one as it ends (in the calling
/// thread). Returns whether the sweep was interrupted.
pub fn run_all(tasks: Vec<Task>, jobs: usize, mut on_done: impl FnMut(Finished)) -> Result<bool> {
    let exe = std::env::current_exe()?;
    let running = Arc::new(Mutex::new(Running::default()));
    let interrupted = Arc::new(AtomicBool::new(false));
    let mut signals = signal_hook::iterator::Signals::new([
        signal_hook::consts::SIGINT,
        signal_hook::consts::SIGTERM,
    ])?;
    let signals_handle = signals.handle();
    let signal_thread = {
        let running = running.clone();
        let interrupted = interrupted.clone();
        std::thread::spawn(move || {
            for _ in signals.forever() {
                interrupted.store(true, Ordering::SeqCst);
                let mut r = running.lock().unwrap();
                r.stopping = true;
                for pid in &r.pids {
                    // SAFETY: signals a child we started and have not reaped yet (it is
                    // removed from `pids` before `wait` returns control to reap it).
                    unsafe { libc::kill(*pid as libc::pid_t, libc::SIGTERM) };
                }
            }
        })
    };

    let (task_tx, task_rx) = unbounded::<Task>();
    for t in tasks {
        task_tx.send(t)?;
    }
    drop(task_tx);
    let (done_tx, done_rx) = unbounded::<Finished>();
    let workers: Vec<_> = (0..jobs.max(1))
        .map(|_| {
            let (tasks, done, running, exe) = (
                task_rx.clone(),
                done_tx.clone(),
                running.clone(),
                exe.clone(),
            );
            std::thread::spawn(move || {
                for task in tasks.iter() {
                    if running.lock().unwrap().stopping {
                        break;
                    }
                    run_one(&exe, task, &running, &done);
                }
            })
        })
        .collect();
    drop(done_tx);
    for finished in done_rx.iter() {
        on_done(finished);
    }
    for w in workers {
        let _ = w.join();
    }
    signals_handle.close();
    let _ = signal_thread.join();
    Ok(interrupted.load(Ordering::SeqCst))
}

fn run_one(exe: &Path, task: Task, running: &Mutex<Running>, done: &Sender<Finished>) {
    let mut finished = Finished {
        cell: task.cell,
        seed: task.seed,
        run_dir: None,
        exit_code: None,
        report: None,
        interrupted: false,
        error: None,
    };
    let started = start(exe, &task, running);
    let child = match started {
        Ok(Some(child)) => child,
        Ok(None) => {
            finished.interrupted = true;
            let _ = done.send(finished);
            return;
        }
        Err(e) => {
            finished.error = Some(format!("cannot start the launch: {e}"));
            let _ = done.send(finished);
            return;
        }
    };
    let status = wait(child, running);
    // The launcher removes its group's shared memory; this is belt and braces for a launcher
    // that was killed.
    let _ = caravan::group::remove_resources(&task.group);
    let stopping = running.lock().unwrap().stopping;
    finished.exit_code = status.as_ref().ok().and_then(|s| s.code());
    if let Err(e) = &status {
        finished.error = Some(format!("cannot wait for the launch: {e}"));
    }
    if let Some((run_dir, report)) = last_run(&task.dir) {
        finished.run_dir = Some(run_dir);
        finished.report = report;
    }
    let outcome = finished
        .report
        .as_ref()
        .map(|r| r["run"]["outcome"].clone());
    // A run the sweep stopped says "interrupted" (or left no report): it is not a result.
    finished.interrupted = stopping
        && outcome
            .as_ref()
            .is_none_or(|o| !matches!(o.as_str(), Some("completed" | "degraded" | "failed")));
    let _ = done.send(finished);
}

/// Starts the launcher, its output going to `launch.log` in its runs dir. `None` when the
/// sweep is stopping.
fn start(
    exe: &Path,
    task: &Task,
    running: &Mutex<Running>,
) -> std::io::Result<Option<std::process::Child>> {
    std::fs::create_dir_all(&task.dir)?;
    let log = std::fs::File::create(task.dir.join("launch.log"))?;
    let mut cmd = Command::new(exe);
    cmd.args(&task.args)
        .stdin(Stdio::null())
        .stdout(log.try_clone()?)
        .stderr(log)
        // Its own process group: a Ctrl-C in the terminal reaches only the sweep, which
        // forwards one SIGTERM, rather than every launcher at once.
        .process_group(0);
    // A sweep killed outright still stops its launchers, which stop their groups cleanly.
    caravan_group::run::supervisor::die_with_parent(&mut cmd, libc::SIGTERM);
    let mut r = running.lock().unwrap();
    if r.stopping {
        return Ok(None);
    }
    let child = cmd.spawn()?;
    r.pids.insert(child.id());
    Ok(Some(child))
}

/// Waits for the child without holding the lock, then forgets its pid. The pid stays
/// registered until reaped, so the signal thread never signals a recycled pid.
fn wait(
    mut child: std::process::Child,
    running: &Mutex<Running>,
) -> std::io::Result<std::process::ExitStatus> {
    let pid = child.id();
    // Block until the child exits but leave it unreaped (WNOWAIT), so its pid cannot be
    // reused while the signal thread may still signal it.
    let mut info: libc::siginfo_t = unsafe { std::mem::zeroed() };
    loop {
        // SAFETY: waits for our own child; `info` is a valid out-pointer.
        let r = unsafe { libc::waitid(libc::P_PID, pid, &mut info, libc::WEXITED | libc::WNOWAIT) };
        if r == 0 || std::io::Error::last_os_error().raw_os_error() != Some(libc::EINTR) {
            break;
        }
    }
    let mut r = running.lock().unwrap();
    r.pids.remove(&pid);
    let status = child.wait();
    drop(r);
    status
}
