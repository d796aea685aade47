//! A real one-node Slurm cluster on this machine, for the tests of what Caravan submits to
//! Slurm.
//!
//! [`Cluster::start`] installs Debian's Slurm and MUNGE packages when they are missing, then
//! runs `munged`, `slurmctld` and `slurmd` as children of the test, in the foreground, on
//! 127.0.0.1 and free ports, with everything they make (configuration, key, sockets, state,
//! spool, logs) in a folder of the cluster's own under the temporary directory; dropping the
//! [`Cluster`] stops them and removes the folder. The cluster writes nothing elsewhere (only
//! the packages' install writes what it writes, under `/etc` too) and the packages' own
//! services are never started, so the fixture works the same with or without an init system.
//! Client commands find the cluster through `SLURM_CONF` ([`Cluster::envs`]). It needs root,
//! as CI has: to install, and because slurmd runs the jobs as their submitter.
//!
//! A test process that is killed cannot clean up: each start removes what such a run left,
//! recognised by the folder name ([`PREFIX`], then the owning test process's pid), the
//! daemons, job steps and jobs that name such a folder in their command line or environment
//! included.

use crate::{alive, hosts::free_port};
use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::io::Read;
use std::os::unix::fs::{OpenOptionsExt, PermissionsExt};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};

/// Start of the name of every cluster folder: `caravan-slurm-<pid>-<name>-<n>`.
pub const PREFIX: &str = "caravan-slurm-";

/// The Debian packages the cluster needs.
const PACKAGES: [&str; 4] = ["slurmctld", "slurmd", "slurm-client", "munge"];

/// Job states after which a job never runs again (`JobState=` of `scontrol show job`).
const FINAL: [&str; 10] = [
    "COMPLETED",
    "FAILED",
    "CANCELLED",
    "TIMEOUT",
    "NODE_FAIL",
    "OUT_OF_MEMORY",
    "PREEMPTED",
    "BOOT_FAIL",
    "DEADLINE",
    "REVOKED",
];

/// A running one-node Slurm cluster; stopped and removed when dropped.
pub struct Cluster {
    /// The cluster's folder: `slurm.conf`, the MUNGE key and socket, state, spool and logs.
    pub dir: PathBuf,
    /// The name of the node, of its partition (the default one) and of the cluster.
    pub node: String,
    /// The daemons, in the order they were started.
    daemons: Vec<(&'static str, Child)>,
}

impl Cluster {
    /// Installs the packages if needed, writes the configuration, starts the daemons and
    /// waits until the node is idle. `name` (letters and digits) names the node; it need not
    /// be unique. Panics with the daemons' logs if the cluster does not come up within a
    /// minute.
    pub fn start(name: &str) -> Cluster {
        let started = Instant::now();
        assert!(
            !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric()),
            "a cluster's name is letters and digits: {name:?}"
        );
        remove_leftovers();
        install();
        static COUNTER: AtomicU32 = AtomicU32::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("{PREFIX}{}-{name}-{n}", std::process::id()));
        std::fs::create_dir(&dir).expect("create the cluster's folder");
        // The folder exists before anything can fail, so a panic below still removes it.
        let mut cluster = Cluster {
            dir,
            node: name.to_ascii_lowercase(),
            daemons: Vec::new(),
        };
        cluster.configure();
        let dir = cluster.dir.clone();
        let path = |f: &str| dir.join(f).display().to_string();

        // A `--force`d munged, since it otherwise refuses to run as root.
        let munged = Command::new(program("munged"));
        cluster.spawn("munged", munged, |c| {
            c.args(["--foreground", "--force"])
                .args(["--socket", &path("munge.socket.2")])
                .args(["--key-file", &path("munge.key")])
                .args(["--pid-file", &path("munged.pid")])
                .args(["--log-file", &path("munged.log")])
                .args(["--seed-file", &path("munged.seed")]);
        });
        cluster.wait("munged listens", Duration::from_secs(30), |c| {
            c.dir.join("munge.socket.2").exists()
        });
        cluster.spawn("slurmctld", Command::new(program("slurmctld")), |c| {
            c.args(["-D", "-f", &path("slurm.conf")]);
        });
        let node = cluster.node.clone();
        cluster.spawn("slurmd", Command::new(program("slurmd")), |c| {
            c.args(["-D", "-N", &node, "-f", &path("slurm.conf")]);
        });
        cluster.wait("the node is idle", Duration::from_secs(60), |c| {
            let out = c.command("sinfo").args(["-h", "-N", "-o", "%T"]).output();
            out.is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "idle")
        });
        let took = started.elapsed().as_secs_f64();
        eprintln!("slurm: cluster {} up in {took:.1} s", cluster.dir.display());
        cluster
    }

    /// The environment Slurm's client commands need to use this cluster.
    pub fn envs(&self) -> Vec<(String, String)> {
        vec![(
            "SLURM_CONF".into(),
            self.dir.join("slurm.conf").display().to_string(),
        )]
    }

    /// A Slurm client command (`sbatch`, `squeue`, …) set up for this cluster.
    pub fn command(&self, program: &str) -> Command {
        let mut cmd = Command::new(program);
        cmd.envs(self.envs()).stdin(Stdio::null());
        cmd
    }

    /// Runs `sbatch --parsable args…` and returns the job id; panics with sbatch's message
    /// if it fails.
    pub fn submit(&self, args: &[&str]) -> String {
        let out = self.run("sbatch", &[&["--parsable"], args].concat());
        let text = String::from_utf8_lossy(&out.stdout);
        // `--parsable` prints `<id>` or `<id>;<cluster>`.
        text.trim().split(';').next().unwrap_or("").to_string()
    }

    /// Waits until job `id` (every task, if it is an array) has left the queue and returns
    /// each task's final state, ordered by task id: `(array task id, state)`, or
    /// `(job id, state)` for a job that is no array; the part of an array that never started
    /// (cancelled while pending) comes as one range, like `("2-3", "CANCELLED")`. Panics after
    /// `timeout`.
    ///
    /// With no accounting daemon, `sacct` knows nothing ("accounting storage is disabled"),
    /// so the states come from `scontrol show job`, which keeps a finished job for
    /// `MinJobAge` (five minutes), and after that from the job completion log.
    pub fn wait_for_job(&self, id: &str, timeout: Duration) -> Vec<(String, String)> {
        let mut states = Vec::new();
        let what = format!("job {id} has left the queue");
        self.wait(&what, timeout, |c| {
            // `squeue` lists a job while it is pending, running or completing; a job that
            // slurmctld has forgotten is an error.
            let Ok(queued) = c.command("squeue").args(["-h", "-j", id]).output() else {
                return false;
            };
            let forgotten = String::from_utf8_lossy(&queued.stderr).contains("Invalid job id");
            if !(queued.status.success() || forgotten) || !queued.stdout.is_empty() {
                return false;
            }
            states = c.job_states(id);
            !states.is_empty() && states.iter().all(|(_, s)| FINAL.contains(&s.as_str()))
        });
        states
    }

    /// `(task, state)` of each record of job `id`: from `scontrol` while it knows the job,
    /// else from the job completion log (same `Key=value` words).
    fn job_states(&self, id: &str) -> Vec<(String, String)> {
        let out = self
            .command("scontrol")
            .args(["-o", "show", "job", id])
            .output();
        let mut text = out.map_or(String::new(), |o| String::from_utf8_lossy(&o.stdout).into());
        let field = |line: &str, key: &str| {
            line.split_whitespace()
                .find_map(|w| w.strip_prefix(key)?.strip_prefix('='))
                .map(str::to_string)
        };
        if !text.contains("JobState=") {
            text = std::fs::read_to_string(self.dir.join("jobcomp.txt")).unwrap_or_default();
        }
        let mut states: Vec<(String, String)> = text
            .lines()
            .filter(|l| [field(l, "JobId"), field(l, "ArrayJobId")].contains(&Some(id.into())))
            .filter_map(|l| {
                let task = field(l, "ArrayTaskId").or(field(l, "JobId"))?;
                Some((task, field(l, "JobState")?))
            })
            .collect();
        // Numerically, a range (`2-3`) by its first task.
        let first = |t: &str| t.split(['-', ',']).next()?.parse::<u64>().ok();
        states.sort_by_key(|(task, _)| (first(task), task.clone()));
        states
    }

    /// Runs a client command to its end; panics with its output unless it succeeds.
    pub fn run(&self, program: &str, args: &[&str]) -> Output {
        let out = self
            .command(program)
            .args(args)
            .output()
            .unwrap_or_else(|e| panic!("cannot run {program}: {e}"));
        assert!(
            out.status.success(),
            "{program} {args:?} failed: {}{}\n{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr),
            self.logs()
        );
        out
    }

    /// The last lines of every log in the cluster's folder, for a failure's message.
    pub fn logs(&self) -> String {
        let mut text = String::new();
        let mut files: Vec<PathBuf> = std::fs::read_dir(&self.dir)
            .into_iter()
            .flatten()
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|e| e == "log" || e == "out"))
            .collect();
        files.sort();
        for file in files {
            let content = std::fs::read_to_string(&file).unwrap_or_default();
            let lines: Vec<&str> = content.lines().collect();
            let tail = &lines[lines.len().saturating_sub(40)..];
            let name = file.file_name().unwrap_or_default().to_string_lossy();
            let _ = write!(text, "\n--- {name} ---\n{}\n", tail.join("\n"));
        }
        text
    }

    /// Writes the MUNGE key and `slurm.conf` (with `cgroup.conf`, which slurmd reads in
    /// any case) into the folder.
    fn configure(&self) {
        let mut key = [0u8; 1024];
        std::fs::File::open("/dev/urandom")
            .and_then(|mut f| f.read_exact(&mut key))
            .expect("read /dev/urandom");
        // munged refuses a key that others can read.
        std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .mode(0o600)
            .open(self.dir.join("munge.key"))
            .and_then(|mut f| std::io::Write::write_all(&mut f, &key))
            .expect("write the MUNGE key");
        // slurmctld accepts to be the controller only on the host SlurmctldHost names.
        let host = std::fs::read_to_string("/proc/sys/kernel/hostname").expect("hostname");
        let host = host.trim().split('.').next().unwrap_or("localhost");
        let (ctld_port, slurmd_port) = loop {
            let (a, b) = (free_port(), free_port());
            if a != b {
                break (a, b);
            }
        };
        let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
        let (d, node) = (self.dir.display(), &self.node);
        let conf = format!(
            "# One node on loopback, written by caravan-tests; everything lives in this folder.
ClusterName={node}
SlurmctldHost={host}(127.0.0.1)
SlurmctldPort={ctld_port}
SlurmdPort={slurmd_port}
# Daemons listen on their configured address (127.0.0.1) only, not on every interface.
CommunicationParameters=NoCtldInAddrAny,NoInAddrAny
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket={d}/munge.socket.2
CredType=cred/munge
StateSaveLocation={d}/state
SlurmdSpoolDir={d}/spool
SlurmctldPidFile={d}/slurmctld.pid
SlurmdPidFile={d}/slurmd.pid
SlurmctldLogFile={d}/slurmctld.log
SlurmdLogFile={d}/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
# No cgroups, no accounting daemon: whatever a test machine or container allows.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc={d}/jobcomp.txt
MpiDefault=none
SwitchType=switch/none
MailProg=/bin/true
# Several tasks of an array share the node, one CPU each.
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
# The node's configured CPUs count even if the hardware is found to differ.
SlurmdParameters=config_overrides
ReturnToService=2
# Schedule at once on submission and completion (by default up to 3 s later), and give a
# cancelled job 5 s, not 30, between SIGTERM and SIGKILL.
SchedulerParameters=batch_sched_delay=0
KillWait=5
NodeName={node} NodeAddr=127.0.0.1 NodeHostname={host} CPUs={cpus} State=UNKNOWN
PartitionName={node} Nodes={node} Default=YES MaxTime=INFINITE State=UP
"
        );
        std::fs::write(self.dir.join("slurm.conf"), conf).expect("write slurm.conf");
        // Slurm 22.05's slurmd loads a cgroup plugin even when no other plugin uses it (there
        // is no CgroupPlugin=disabled before 23.02); with cgroup v2 it would ask systemd to
        // make a scope unless told not to.
        std::fs::write(
            self.dir.join("cgroup.conf"),
            "CgroupPlugin=autodetect\nIgnoreSystemd=yes\n",
        )
        .expect("write cgroup.conf");
        for sub in ["state", "spool"] {
            std::fs::create_dir(self.dir.join(sub)).expect("create a state folder");
        }
    }

    /// Starts a daemon with its output in `<name>.out`, in the cluster's environment.
    fn spawn(&mut self, name: &'static str, mut cmd: Command, args: impl FnOnce(&mut Command)) {
        args(&mut cmd);
        let out = std::fs::File::create(self.dir.join(format!("{name}.out"))).expect("log file");
        let child = cmd
            .envs(self.envs())
            .stdin(Stdio::null())
            .stdout(out.try_clone().expect("log file"))
            .stderr(out)
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {name}: {e}"));
        self.daemons.push((name, child));
    }

    /// Polls `cond` every 100 ms until it holds; panics with the logs if `timeout` passes or
    /// a daemon exits first.
    fn wait(&self, what: &str, timeout: Duration, mut cond: impl FnMut(&Self) -> bool) {
        let end = Instant::now() + timeout;
        loop {
            if cond(self) {
                return;
            }
            for (name, child) in &self.daemons {
                // An exited child is a zombie until Drop reaps it.
                if !alive(child.id() as i32) {
                    panic!("{name} exited before {what}{}", self.logs());
                }
            }
            if Instant::now() > end {
                let queue = self.command("squeue").arg("-a").output();
                let queue = queue.map(|o| String::from_utf8_lossy(&o.stdout).into_owned());
                panic!(
                    "timed out after {timeout:?} waiting until {what}\nsqueue: {}{}",
                    queue.unwrap_or_default(),
                    self.logs()
                );
            }
            std::thread::sleep(Duration::from_millis(100));
        }
    }
}

impl Drop for Cluster {
    /// Stops the daemons (SIGTERM, SIGKILL after five seconds), kills what is left of the
    /// cluster's jobs (their `slurmstepd`s are no children of slurmd's), removes the folder.
    fn drop(&mut self) {
        for (_, child) in self.daemons.iter_mut().rev() {
            crate::terminate(child);
            let end = Instant::now() + Duration::from_secs(5);
            while matches!(child.try_wait(), Ok(None)) && Instant::now() < end {
                std::thread::sleep(Duration::from_millis(50));
            }
            let _ = child.kill();
            let _ = child.wait();
        }
        let folder = self
            .dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned());
        kill_marked(|name, _| Some(name) == folder.as_deref());
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// Removes what killed test runs left: processes naming a cluster folder whose owner is dead,
/// then such folders.
fn remove_leftovers() {
    kill_marked(|_, owner| !alive(owner));
    for entry in std::fs::read_dir(std::env::temp_dir())
        .into_iter()
        .flatten()
    {
        let Ok(entry) = entry else { continue };
        let name = entry.file_name().to_string_lossy().into_owned();
        if owner(&name).is_some_and(|pid| !alive(pid)) {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}

/// The pid in a cluster folder's name (`caravan-slurm-<pid>-…`).
fn owner(folder: &str) -> Option<i32> {
    let (pid, _) = folder.strip_prefix(PREFIX)?.split_once('-')?;
    pid.parse().ok()
}

/// Sends SIGKILL to every other process whose command line or environment names a cluster
/// folder for which `doomed(folder name, owner pid)` holds, and waits (two seconds at most)
/// until they are gone.
fn kill_marked(doomed: impl Fn(&str, i32) -> bool) {
    let me = std::process::id() as i32;
    let mut killed = Vec::new();
    for entry in std::fs::read_dir("/proc").into_iter().flatten().flatten() {
        let Some(pid) = entry
            .file_name()
            .to_str()
            .and_then(|p| p.parse::<i32>().ok())
        else {
            continue;
        };
        if pid == me {
            continue;
        }
        let mut text = std::fs::read(entry.path().join("cmdline")).unwrap_or_default();
        text.extend(std::fs::read(entry.path().join("environ")).unwrap_or_default());
        let text = String::from_utf8_lossy(&text);
        let marked = text.match_indices(PREFIX).any(|(at, _)| {
            let name = text[at..].split(['/', '\0', ' ']).next().unwrap_or("");
            owner(name).is_some_and(|o| doomed(name, o))
        });
        if marked {
            // SAFETY: signalling a process; at worst one that has just exited.
            unsafe { libc::kill(pid, libc::SIGKILL) };
            killed.push(pid);
        }
    }
    let end = Instant::now() + Duration::from_secs(2);
    while killed.iter().any(|&p| alive(p)) && Instant::now() < end {
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// The path of `name` in PATH or an sbin directory (not every PATH has the daemons).
fn program(name: &str) -> PathBuf {
    let path = std::env::var("PATH").unwrap_or_default();
    let dirs = path.split(':').chain(["/usr/sbin", "/sbin", "/usr/bin"]);
    dirs.map(|d| Path::new(d).join(name))
        .find(|p| p.is_file())
        .unwrap_or_else(|| PathBuf::from(name))
}

/// Pids of the processes named like one of Slurm's or MUNGE's daemons.
fn daemon_pids() -> BTreeSet<i32> {
    let names = ["munged", "slurmctld", "slurmd", "slurmstepd"];
    std::fs::read_dir("/proc")
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let pid = e.file_name().to_str()?.parse().ok()?;
            let comm = std::fs::read_to_string(e.path().join("comm")).ok()?;
            names.contains(&comm.trim()).then_some(pid)
        })
        .collect()
}

/// Installs [`PACKAGES`] unless their programs are there, one test process at a time (the
/// others wait on a lock), without starting the packages' services.
fn install() {
    let tools = [
        "munged",
        "slurmctld",
        "slurmd",
        "sbatch",
        "scontrol",
        "sinfo",
    ];
    let missing = || tools.iter().any(|t| !program(t).is_absolute());
    if !missing() {
        return;
    }
    let lock_path = std::env::temp_dir().join("caravan-slurm.install.lock");
    let lock = std::fs::File::create(&lock_path).expect("create the install lock");
    // SAFETY: flock on a file this function holds open; released when it is closed.
    let locked = unsafe { libc::flock(std::os::fd::AsRawFd::as_raw_fd(&lock), libc::LOCK_EX) };
    assert_eq!(locked, 0, "cannot lock {}", lock_path.display());
    if !missing() {
        return;
    }
    let started = Instant::now();
    let before = daemon_pids();
    // Without systemd, the postinst scripts start the services through invoke-rc.d unless
    // policy-rc.d forbids it (exit 101). Containers usually have one; if not, one is put in
    // place for the install.
    let policy = Path::new("/usr/sbin/policy-rc.d");
    let own_policy = !policy.exists();
    if own_policy {
        std::fs::write(
            policy,
            "#!/bin/sh\n# caravan-tests: no services while installing\nexit 101\n",
        )
        .expect("write policy-rc.d");
        std::fs::set_permissions(policy, std::fs::Permissions::from_mode(0o755))
            .expect("chmod policy-rc.d");
    }
    let apt = |args: &[&str]| {
        let out = Command::new("apt-get")
            .args(args)
            .env("DEBIAN_FRONTEND", "noninteractive")
            .stdin(Stdio::null())
            .output();
        match out {
            Ok(o) if o.status.success() => Ok(()),
            Ok(o) => Err(format!(
                "apt-get {args:?} failed ({}): {}{}",
                o.status,
                String::from_utf8_lossy(&o.stdout),
                String::from_utf8_lossy(&o.stderr)
            )),
            Err(e) => Err(format!("cannot run apt-get: {e}")),
        }
    };
    let result = apt(&["update", "-qq"]).and_then(|()| {
        apt(&[
            &["install", "-y", "-qq", "--no-install-recommends"],
            &PACKAGES[..],
        ]
        .concat())
    });
    if own_policy {
        let _ = std::fs::remove_file(policy);
    }
    // Whatever a postinst started anyway (an init system ignoring the policy) is stopped.
    for pid in daemon_pids().difference(&before) {
        // SAFETY: signalling a daemon the install just started.
        unsafe { libc::kill(*pid, libc::SIGTERM) };
    }
    if let Err(e) = result {
        panic!("installing Slurm ({}) failed: {e}", PACKAGES.join(" "));
    }
    assert!(
        !missing(),
        "Slurm's programs are missing after installing it"
    );
    eprintln!(
        "slurm: installed {} in {:.1} s",
        PACKAGES.join(" "),
        started.elapsed().as_secs_f64()
    );
}
