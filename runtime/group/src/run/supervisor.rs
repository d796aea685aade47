//! The supervisor: spawns the group's processes, reaps them promptly, applies restart
//! policies and stops them (SIGTERM, then SIGKILL after the grace period).

use super::output::Console;
use caravan_launch::model::{ProcessSpec, Restart};
use caravan_report::ProcessRecord;
use crossbeam::channel::Sender;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fs::File;
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitStatus, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Something the launcher's main loop reacts to.
pub enum Event {
    Exited {
        index: usize,
        generation: u32,
        status: ExitStatus,
        usage: Usage,
        /// The last line the process wrote to stderr.
        last_error: String,
    },
    Signal(i32),
    /// Lockstep nodes that did not finish the step at `now_ns` within `timeout`.
    Hung {
        names: Vec<String>,
        now_ns: u64,
        timeout: Duration,
    },
    /// Realtime Caravan nodes that have not published a status within `timeout` of the start.
    Silent {
        names: Vec<String>,
        timeout: Duration,
    },
    /// The lockstep schedule or the realtime recorder finished (or failed).
    DriverDone(Result<(), String>),
    /// The other hosts of a group on several machines did something.
    Fleet(caravan_bridge::FleetEvent),
}

/// Resources a process used, from the kernel's accounting at exit (wait4).
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize)]
pub struct Usage {
    /// User + system CPU time, s.
    pub cpu_s: f64,
    /// Peak resident set size, MiB.
    pub max_rss_mib: f64,
}

/// Waits for `pid` to exit; returns its status and resource usage.
fn reap(pid: i32) -> std::io::Result<(ExitStatus, Usage)> {
    let mut status = 0;
    // SAFETY: rusage is plain data that wait4 fills in.
    let mut ru: libc::rusage = unsafe { std::mem::zeroed() };
    loop {
        // SAFETY: waits for our own child; the pointers are valid for the call.
        let r = unsafe { libc::wait4(pid, &mut status, 0, &mut ru) };
        if r == pid {
            break;
        }
        let e = std::io::Error::last_os_error();
        if e.kind() != std::io::ErrorKind::Interrupted {
            return Err(e);
        }
    }
    let usage = Usage {
        cpu_s: caravan_report::bench::cpu_seconds(&ru),
        max_rss_mib: ru.ru_maxrss as f64 / 1024.0,
    };
    Ok((ExitStatus::from_raw(status), usage))
}

/// One process to run: its spec and the resolved program and arguments.
pub struct Planned {
    pub spec: ProcessSpec,
    pub program: PathBuf,
    pub args: Vec<String>,
    /// A container's nodes (launch key `container`), whose process this is: `spec` is then
    /// the first member's, named after the container. Empty for a process of one node.
    pub members: Vec<ProcessSpec>,
}

/// Puts the nodes of each container into one process, where the first member was (see
/// `caravan::container`). Containers step in lockstep only: in realtime each node keeps a
/// process of its own, as without the key.
pub fn containers(plans: Vec<Planned>, lockstep: bool) -> Vec<Planned> {
    let mut out: Vec<Planned> = Vec::new();
    let mut at: BTreeMap<String, usize> = BTreeMap::new();
    for plan in plans {
        let Some(name) = plan.spec.container.clone().filter(|_| lockstep) else {
            out.push(plan);
            continue;
        };
        match at.get(&name) {
            Some(&i) => out[i].members.push(plan.spec),
            None => {
                at.insert(name.clone(), out.len());
                let mut spec = plan.spec.clone();
                spec.name = name;
                spec.required = false;
                out.push(Planned {
                    spec,
                    members: vec![plan.spec],
                    ..plan
                });
            }
        }
    }
    for plan in &mut out {
        // One member failing for good fails the container, so the container is required if
        // any member is.
        if !plan.members.is_empty() {
            plan.spec.required = plan.members.iter().any(|m| m.required);
        }
    }
    out
}

impl Planned {
    /// The command that starts the process: its program, arguments and environment (`env`,
    /// what every process of the group gets, then its own), stdin closed, in a process group of
    /// its own that gets `parent_death` when the launcher dies.
    pub fn command(&self, env: &BTreeMap<String, String>, parent_death: libc::c_int) -> Command {
        let spec = &self.spec;
        let mut cmd = Command::new(&self.program);
        cmd.args(&self.args)
            .envs(env)
            .env(caravan::env_vars::NODE, &spec.name)
            .env(caravan::env_vars::HOST, &spec.host)
            .envs(&spec.env)
            .stdin(Stdio::null())
            // Own process group: Ctrl-C reaches the launcher only, which stops the group in
            // order instead of every process racing to exit; and stopping the group signals
            // whatever the process started too.
            .process_group(0);
        // If the launcher is killed (even with SIGKILL) its processes get the signal instead
        // of living on as orphans holding the group's shared memory.
        die_with_parent(&mut cmd, parent_death);
        if !self.members.is_empty() {
            let members: Vec<caravan::container::Member> = self
                .members
                .iter()
                .map(|m| caravan::container::Member {
                    node: m.name.clone(),
                    params: m.params.clone(),
                    rate: m.rate.clone(),
                    on: m.on.clone(),
                })
                .collect();
            let text = serde_json::to_string(&members).expect("members serialise");
            cmd.env(caravan::env_vars::CONTAINER, text);
            return cmd;
        }
        cmd.env(caravan::env_vars::PARAMS, spec.params.to_string());
        if let Some(rate) = &spec.rate {
            cmd.env(caravan::env_vars::RATE, rate);
        }
        if let Some(on) = &spec.on {
            cmd.env(caravan::env_vars::ON, on);
        }
        if let Some(spin) = spec.spin {
            cmd.env(caravan::env_vars::SPIN, caravan::spin::spin_text(spin));
        }
        cmd
    }
}

/// Has `cmd`'s process receive `signal` when the thread that started it dies, however it dies.
pub fn die_with_parent(cmd: &mut Command, signal: libc::c_int) {
    // SAFETY: prctl is async-signal-safe; it only sets this child's parent-death signal.
    unsafe {
        cmd.pre_exec(move || {
            if libc::prctl(libc::PR_SET_PDEATHSIG, signal) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
}

struct Proc {
    plan: Planned,
    pid: Option<i32>,
    generation: u32,
    restarts: u32,
    last_status: Option<ExitStatus>,
    restart_at: Option<Instant>,
    log: Arc<Mutex<File>>,
    usage: Usage,
}

pub struct Supervisor {
    procs: Vec<Proc>,
    /// Every process group started (one per spawn, led by the spawned process): what a process
    /// left running in its group is killed when the group ends.
    groups: Vec<i32>,
    env: BTreeMap<String, String>,
    events: Sender<Event>,
    console: Console,
}

/// Signals the process group that `leader` (a process we spawned) leads: the process and
/// whatever it started. A process group's id is not reused while any of its members lives.
fn signal_group(leader: i32, signal: i32) {
    // SAFETY: kill(2) with a negative pid signals that process group; no memory is touched.
    unsafe { libc::kill(-leader, signal) };
}

fn describe(status: &ExitStatus) -> String {
    match (status.code(), status.signal()) {
        (Some(code), _) => format!("exited {code}"),
        (None, Some(sig)) => format!("killed by signal {sig}"),
        _ => "ended".into(),
    }
}

impl Supervisor {
    /// `env` is what every process gets (group, config path, clock…); each adds its own.
    pub fn new(
        plans: Vec<Planned>,
        env: BTreeMap<String, String>,
        logs: &Path,
        events: Sender<Event>,
        console: Console,
    ) -> std::io::Result<Self> {
        let mut procs = Vec::new();
        for plan in plans {
            let log = File::create(logs.join(format!("{}.log", plan.spec.name)))?;
            procs.push(Proc {
                plan,
                pid: None,
                generation: 0,
                restarts: 0,
                last_status: None,
                restart_at: None,
                log: Arc::new(Mutex::new(log)),
                usage: Usage::default(),
            });
        }
        Ok(Self {
            procs,
            groups: Vec::new(),
            env,
            events,
            console,
        })
    }

    /// The group's nodes: each process's, or its container's members.
    pub fn names(&self) -> Vec<String> {
        (0..self.procs.len())
            .flat_map(|i| self.nodes_of(i))
            .collect()
    }

    /// The nodes process `index` runs: itself, or its container's members.
    pub fn nodes_of(&self, index: usize) -> Vec<String> {
        let plan = &self.procs[index].plan;
        if plan.members.is_empty() {
            return vec![plan.spec.name.clone()];
        }
        plan.members.iter().map(|m| m.name.clone()).collect()
    }

    /// The process that runs node `name`: its own, or its container's.
    fn process_of(&self, name: &str) -> Option<&Proc> {
        self.procs.iter().find(|p| {
            p.plan.spec.name == name && p.plan.members.is_empty()
                || p.plan.members.iter().any(|m| m.name == name)
        })
    }

    pub fn start_all(&mut self) -> std::io::Result<()> {
        for i in 0..self.procs.len() {
            self.spawn(i)?;
        }
        Ok(())
    }

    fn spawn(&mut self, index: usize) -> std::io::Result<()> {
        let prefix = self
            .console
            .prefix(index, &self.procs[index].plan.spec.name);
        let p = &mut self.procs[index];
        let mut child = p
            .plan
            // SIGTERM: a node stops cleanly, leaving its shared memory to the clean-up.
            .command(&self.env, libc::SIGTERM)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()?;
        self.console.pump(
            child.stdout.take().expect("piped"),
            prefix.clone(),
            p.log.clone(),
        );
        let (last_error, stderr_eof) =
            self.console
                .pump(child.stderr.take().expect("piped"), prefix, p.log.clone());
        p.pid = Some(child.id() as i32);
        p.generation += 1;
        self.groups.push(child.id() as i32);
        let (events, generation) = (self.events.clone(), p.generation);
        // One reaper per child: it is reaped the moment it exits, so no zombie keeps
        // iceoryx2's process locks alive.
        let pid = child.id() as i32;
        drop(child); // std never reaps on drop; `reap` does, with resource usage.
        std::thread::spawn(move || {
            if let Ok((status, usage)) = reap(pid) {
                // Let the last lines of stderr arrive (a grandchild may hold the pipe open,
                // so do not wait long): they explain the exit.
                let _ = stderr_eof.recv_timeout(Duration::from_millis(300));
                let last_error = last_error.lock().map(|l| l.clone()).unwrap_or_default();
                let _ = events.send(Event::Exited {
                    index,
                    generation,
                    status,
                    usage,
                    last_error,
                });
            }
        });
        Ok(())
    }

    /// Records an exit. Returns the restart time if the policy restarts it, or `Err(name)` if
    /// a required process failed for good.
    pub fn on_exit(
        &mut self,
        index: usize,
        generation: u32,
        status: ExitStatus,
        usage: Usage,
        last_error: &str,
        stopping: bool,
    ) -> Result<Option<Instant>, String> {
        let p = &mut self.procs[index];
        p.usage.cpu_s += usage.cpu_s;
        p.usage.max_rss_mib = p.usage.max_rss_mib.max(usage.max_rss_mib);
        if generation != p.generation {
            return Ok(None);
        }
        p.pid = None;
        p.last_status = Some(status);
        let spec = &p.plan.spec;
        if stopping {
            return Ok(None);
        }
        let why = if status.success() || last_error.is_empty() {
            describe(&status)
        } else {
            format!("{}: {last_error}", describe(&status))
        };
        self.console.say(&format!("process '{}' {why}", spec.name));
        let wants = match spec.restart {
            Restart::Never => false,
            Restart::OnFailure => !status.success(),
            Restart::Always => true,
        };
        if wants && p.restarts < spec.max_restarts {
            // Exponential back-off, capped, so a crash loop does not eat the machine.
            let delay = spec
                .restart_backoff
                .saturating_mul(1 << p.restarts.min(6))
                .min(Duration::from_secs(30));
            p.restarts += 1;
            self.console.say(&format!(
                "restarting '{}' in {:?} ({}/{})",
                spec.name, delay, p.restarts, spec.max_restarts
            ));
            let at = Instant::now() + delay;
            p.restart_at = Some(at);
            return Ok(Some(at));
        }
        if spec.required && !status.success() {
            return Err(format!("required process '{}' {why}", spec.name));
        }
        Ok(None)
    }

    /// Restarts processes whose back-off elapsed; returns the next pending restart time.
    pub fn restart_due(&mut self, now: Instant) -> std::io::Result<Option<Instant>> {
        for i in 0..self.procs.len() {
            if self.procs[i].restart_at.is_some_and(|t| t <= now) {
                self.procs[i].restart_at = None;
                self.spawn(i)?;
            }
        }
        Ok(self.procs.iter().filter_map(|p| p.restart_at).min())
    }

    pub fn any_alive(&self) -> bool {
        self.procs.iter().any(|p| p.pid.is_some())
    }

    /// True when every process ended and none waits for a restart.
    pub fn all_done(&self) -> bool {
        self.procs
            .iter()
            .all(|p| p.pid.is_none() && p.restart_at.is_none())
    }

    /// Whether node `name`'s process runs now.
    pub fn is_running(&self, name: &str) -> bool {
        self.process_of(name).is_some_and(|p| p.pid.is_some())
    }

    /// Sends SIGKILL to node `name`'s process (its container's: the members live and die
    /// together), if it runs.
    pub fn kill(&mut self, name: &str) {
        if let Some(pid) = self.process_of(name).and_then(|p| p.pid) {
            signal_group(pid, libc::SIGKILL);
        }
    }

    pub fn signal_all(&mut self, signal: i32) {
        for p in &mut self.procs {
            p.restart_at = None;
            if let Some(pid) = p.pid {
                signal_group(pid, signal);
            }
        }
    }

    /// Kills what the group's processes left behind in their process groups (a child started
    /// in the background that outlived its parent). Call once every process has exited.
    pub fn kill_leftovers(&mut self) {
        for group in self.groups.drain(..) {
            signal_group(group, libc::SIGKILL);
        }
    }

    /// One record per node; a container's members share its process's exit, CPU and memory.
    pub fn records(&self) -> Vec<ProcessRecord> {
        let mut records = Vec::new();
        for p in &self.procs {
            let record = |spec: &ProcessSpec, container: Option<String>| ProcessRecord {
                name: spec.name.clone(),
                host: spec.host.clone(),
                required: spec.required,
                restarts: p.restarts,
                exit_status: match (&p.last_status, p.pid) {
                    (_, Some(_)) => "running".into(),
                    (Some(s), None) => describe(s),
                    (None, None) => "never started".into(),
                },
                success: p.last_status.is_some_and(|s| s.success()),
                cpu_s: p.usage.cpu_s,
                max_rss_mib: p.usage.max_rss_mib,
                container,
            };
            if p.plan.members.is_empty() {
                records.push(record(&p.plan.spec, None));
            }
            for m in &p.plan.members {
                records.push(record(m, Some(p.plan.spec.name.clone())));
            }
        }
        records
    }
}
