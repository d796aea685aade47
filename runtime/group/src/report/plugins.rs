//! Running the launch file's report plugins (`[[report]]`): `PROGRAM --check` before the
//! group starts, `PROGRAM RUN_DIR` after it ends. See the `caravan-report` crate for the
//! protocol a plugin follows.

use caravan_report::{ReportEntry, Section};
use std::io::Read;
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::sync::mpsc::RecvTimeoutError;
use std::time::{Duration, Instant};

/// A section a plugin wrote, with its JSON text as written.
pub struct Written {
    pub section: Section,
    pub text: String,
}

/// What the plugins wrote, in plugin order (each plugin's sections by name), and which
/// failed (`(exec, message)`).
pub struct Outcome {
    pub sections: Vec<Written>,
    pub failures: Vec<(String, String)>,
}

/// Checks a plugin's params before the run: `Err` holds the plugin's own message.
pub fn check(entry: &ReportEntry) -> Result<(), String> {
    let output = run(entry, &["--check".into()], false)?;
    if output.status.success() {
        Ok(())
    } else {
        Err(message(&output))
    }
}

/// Runs every plugin on `run_dir`, after clearing the sections a previous report left;
/// `quiet`: without saying that it waits for a slow one.
pub fn run_all(run_dir: &Path, entries: &[ReportEntry], quiet: bool) -> Outcome {
    let _ = std::fs::remove_dir_all(run_dir.join(caravan_report::SECTIONS_DIR));
    let mut outcome = Outcome {
        sections: Vec::new(),
        failures: Vec::new(),
    };
    for entry in entries {
        let exec = entry.exec.join(" ");
        let before = caravan_report::written(run_dir);
        let arg = std::path::absolute(run_dir).unwrap_or_else(|_| run_dir.to_path_buf());
        match run(entry, &[arg.display().to_string()], quiet) {
            Ok(output) if output.status.success() => {}
            Ok(output) => {
                outcome.failures.push((exec, message(&output)));
                continue;
            }
            Err(why) => {
                outcome.failures.push((exec, why));
                continue;
            }
        }
        for name in caravan_report::written(run_dir) {
            if before.contains(&name) {
                continue;
            }
            if outcome.sections.iter().any(|w| w.section.name == name) {
                let why = format!("section '{name}' was already written by another plugin");
                outcome.failures.push((exec.clone(), why));
                continue;
            }
            match Section::read(run_dir, &name) {
                Ok((section, text)) => outcome.sections.push(Written { section, text }),
                Err(e) => outcome.failures.push((exec.clone(), format!("{e:#}"))),
            }
        }
    }
    outcome
}

/// When the launcher first says that it waits for a plugin, and how often after that: a
/// plugin's usual run takes a second or two, so a longer wait is said before it looks like a
/// hang.
const PROGRESS_FIRST: Duration = Duration::from_secs(5);
const PROGRESS_EVERY: Duration = Duration::from_secs(15);

/// Runs the plugin with `args` and waits for it, at most its `timeout_s`: past that the
/// plugin (and whatever it started: it runs in a process group of its own) is killed, and it
/// has failed. When it ends in time, what it left running in its group is killed. A plugin
/// running long is said after [`PROGRESS_FIRST`] and every [`PROGRESS_EVERY`], so a launcher
/// waiting for one is never silent, unless `quiet` (`caravan launch --quiet`).
fn run(entry: &ReportEntry, args: &[String], quiet: bool) -> Result<Output, String> {
    let Some((first, rest)) = entry.exec.split_first() else {
        return Err("the command is empty".into());
    };
    let program = crate::run::exec::program(first, Path::new(&entry.launch_dir));
    let mut child = Command::new(&program)
        .args(rest)
        .args(args)
        .env(caravan::env_vars::PARAMS, entry.params.to_string())
        .env(caravan::env_vars::LAUNCH_DIR, &entry.launch_dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .process_group(0)
        .spawn()
        .map_err(|e| format!("cannot run {}: {e}", program.display()))?;
    // Both pipes are drained as the plugin writes, so a chatty plugin never blocks on one.
    let drain = |pipe: Option<Box<dyn Read + Send>>| {
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            if let Some(mut pipe) = pipe {
                let _ = pipe.read_to_end(&mut bytes);
            }
            let _ = tx.send(bytes);
        });
        rx
    };
    let stdout = drain(child.stdout.take().map(|p| Box::new(p) as _));
    let stderr = drain(child.stderr.take().map(|p| Box::new(p) as _));
    let pid = child.id() as i32;
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || tx.send(child.wait()));
    let limit = Duration::from_secs_f64(entry.timeout_s);
    let start = Instant::now();
    let mut say_at = PROGRESS_FIRST;
    let status = loop {
        let left = limit.saturating_sub(start.elapsed());
        let to_say = say_at.saturating_sub(start.elapsed());
        match rx.recv_timeout(left.min(to_say)) {
            Ok(status) => break status.map_err(|e| format!("cannot wait for the plugin: {e}"))?,
            Err(RecvTimeoutError::Timeout) if start.elapsed() >= limit => {
                // SAFETY: signalling the process group this function started.
                unsafe { libc::kill(-pid, libc::SIGKILL) };
                let _ = rx.recv();
                return Err(format!(
                    "did not finish within its time limit of {} s (its entry's `timeout`), and \
                     was killed",
                    limit.as_secs_f64()
                ));
            }
            Err(RecvTimeoutError::Timeout) if start.elapsed() >= say_at => {
                if !quiet {
                    eprintln!(
                        "caravan: waiting for report plugin {} ({:.0} s; its time limit is {} s)",
                        entry.exec.join(" "),
                        start.elapsed().as_secs_f64(),
                        limit.as_secs_f64()
                    );
                }
                say_at += PROGRESS_EVERY;
            }
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => {
                return Err("lost the plugin's process".into());
            }
        }
    };
    // Whatever the plugin left running in its process group is killed: it would hold the
    // pipes open, and the launcher would wait for it past the plugin's time limit.
    // SAFETY: signalling the process group this function started; its id is not reused while
    // any member lives.
    unsafe { libc::kill(-pid, libc::SIGKILL) };
    // A process that left the group (setsid) may still hold a pipe: its output is dropped.
    let collect = |rx: std::sync::mpsc::Receiver<Vec<u8>>| {
        rx.recv_timeout(PIPES_AFTER_EXIT).unwrap_or_default()
    };
    Ok(Output {
        status,
        stdout: collect(stdout),
        stderr: collect(stderr),
    })
}

/// How long the pipes are read after the plugin ended and its process group was killed.
const PIPES_AFTER_EXIT: Duration = Duration::from_secs(5);

/// The plugin's error: its stderr (a plugin prints one paragraph), else its exit status.
fn message(output: &Output) -> String {
    let stderr = String::from_utf8_lossy(&output.stderr);
    let text = stderr.trim();
    if text.is_empty() {
        format!("it {}", output.status)
    } else {
        text.to_string()
    }
}
