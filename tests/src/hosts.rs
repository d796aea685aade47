//! Several "hosts" on one machine, for groups that span hosts (`caravan launch --host`).
//!
//! Each host is a network namespace with its own address, joined to the others by veth
//! pairs on a switch (a bridge device in a namespace of its own), and a mount namespace with
//! its own `/dev/shm` and iceoryx2 directory: its launcher and processes share nothing with
//! the other hosts but the network, as on separate machines. Everything is made by the test
//! and removed when it ends. Where namespaces cannot be made (no privileges), each host gets
//! a user and mount namespace and a loopback port instead; [`Hosts::how`] says which.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};

/// How the hosts are separated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Separation {
    /// Network namespaces and veth pairs: traffic crosses a real (virtual) network.
    Namespaces,
    /// Loopback endpoints, one port per host.
    Loopback,
}

pub struct Hosts {
    names: Vec<String>,
    /// Namespace names: the switch first, then one per host (empty on loopback).
    namespaces: Vec<String>,
    endpoints: Vec<String>,
    pub separation: Separation,
}

/// A loopback TCP port that was free a moment ago.
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port()
}

fn ip(args: &[&str]) -> bool {
    Command::new("ip")
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Removes the namespaces of earlier test processes that are gone (killed by a time limit
/// before their `Drop` ran), with whatever still runs in them, as `caravan clean` does for
/// groups. A namespace is `cv<PID>-…`; one whose test process lives is left alone.
pub fn remove_stale_namespaces() {
    let Ok(out) = Command::new("ip").args(["netns", "list"]).output() else {
        return;
    };
    for line in String::from_utf8_lossy(&out.stdout).lines() {
        let name = line.split_whitespace().next().unwrap_or_default();
        let Some(pid) = name
            .strip_prefix("cv")
            .and_then(|rest| rest.split_once('-'))
            .and_then(|(pid, _)| pid.parse::<u32>().ok())
        else {
            continue;
        };
        if std::path::Path::new(&format!("/proc/{pid}")).exists() {
            continue;
        }
        let pids = Command::new("ip").args(["netns", "pids", name]).output();
        for p in pids
            .map(|o| String::from_utf8_lossy(&o.stdout).into_owned())
            .unwrap_or_default()
            .split_whitespace()
            .filter_map(|p| p.parse::<i32>().ok())
        {
            unsafe { libc::kill(p, libc::SIGKILL) };
        }
        ip(&["netns", "del", name]);
    }
}

impl Hosts {
    /// Hosts named `names`; `tag` keeps this test's namespaces apart from others'.
    pub fn new(tag: &str, names: &[&str]) -> Self {
        remove_stale_namespaces();
        let names: Vec<String> = names.iter().map(|n| n.to_string()).collect();
        let base = format!("cv{}-{tag}", std::process::id());
        let switch = format!("{base}-sw");
        let mut hosts = Self {
            names: names.clone(),
            namespaces: Vec::new(),
            endpoints: Vec::new(),
            separation: Separation::Namespaces,
        };
        if ip(&["netns", "add", &switch]) {
            hosts.namespaces.push(switch.clone());
            let made = ip(&["-n", &switch, "link", "add", "br0", "type", "bridge"])
                && ip(&["-n", &switch, "link", "set", "br0", "up"]);
            assert!(made, "cannot make the switch of namespace {switch}");
            for (i, name) in names.iter().enumerate() {
                let ns = format!("{base}-{i}");
                let port = format!("p{i}");
                let addr = format!("10.88.0.{}", i + 1);
                let made = ip(&["netns", "add", &ns])
                    && ip(&[
                        "link", "add", "eth0", "netns", &ns, "type", "veth", "peer", "name", &port,
                        "netns", &switch,
                    ])
                    && ip(&["-n", &switch, "link", "set", &port, "master", "br0", "up"])
                    && ip(&[
                        "-n",
                        &ns,
                        "addr",
                        "add",
                        &format!("{addr}/24"),
                        "dev",
                        "eth0",
                    ])
                    && ip(&["-n", &ns, "link", "set", "eth0", "up"])
                    && ip(&["-n", &ns, "link", "set", "lo", "up"]);
                hosts.namespaces.push(ns.clone());
                assert!(made, "cannot make host '{name}' as namespace {ns}");
                hosts.endpoints.push(format!("tcp/{addr}:7447"));
            }
        } else {
            hosts.separation = Separation::Loopback;
            for _ in &names {
                hosts
                    .endpoints
                    .push(format!("tcp/127.0.0.1:{}", free_port()));
            }
        }
        eprintln!(
            "hosts {:?} separated by {:?}",
            hosts.names, hosts.separation
        );
        hosts
    }

    pub fn how(&self) -> Separation {
        self.separation
    }

    fn index(&self, host: &str) -> usize {
        self.names
            .iter()
            .position(|n| n == host)
            .expect("a host of this test")
    }

    /// The endpoint host `host` listens on.
    pub fn endpoint(&self, host: &str) -> &str {
        &self.endpoints[self.index(host)]
    }

    /// Starts `caravan launch FILE --host HOST` on `host`, with run directories and files of
    /// the host in `dir`. Standard error is piped; when the launcher has exited, the host
    /// lists what is left in its `/dev/shm` in `dir/shm-HOST.txt`, and the launcher's pid is
    /// in `dir/pid-HOST.txt` while it runs.
    pub fn launch(&self, host: &str, file: &Path, dir: &Path, extra: &[&str]) -> Child {
        let tmp = dir.join(format!("tmp-{host}"));
        std::fs::create_dir_all(&tmp).unwrap();
        std::fs::create_dir_all("/tmp/iceoryx2").ok();
        let script = r#"mount -t tmpfs tmpfs /dev/shm && mount -t tmpfs tmpfs /tmp/iceoryx2 || exit 97
"$@" &
echo $! > "$PIDFILE"
wait $!
rc=$?
ls -A /dev/shm > "$SHMFILE"
exit $rc"#;
        let mut cmd = match self.separation {
            Separation::Namespaces => {
                let mut c = Command::new("ip");
                c.args(["netns", "exec", &self.namespaces[self.index(host) + 1]]);
                c.arg("sh");
                c
            }
            Separation::Loopback => {
                let mut c = Command::new("unshare");
                c.args(["--user", "--map-root-user", "--mount", "sh"]);
                c
            }
        };
        cmd.args(["-c", script, "sh"])
            .arg(crate::workspace_bin("caravan"))
            .args(["launch"])
            .arg(file)
            .args(["--host", host, "--quiet", "--runs-dir"])
            .arg(dir.join(format!("runs-{host}")))
            .args(extra)
            .env("TMPDIR", &tmp)
            .env("PIDFILE", dir.join(format!("pid-{host}.txt")))
            .env("SHMFILE", dir.join(format!("shm-{host}.txt")))
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        cmd.spawn().expect("start a host's launcher")
    }

    /// The run directory of `host` under `dir`.
    pub fn run_dir(&self, host: &str, dir: &Path) -> PathBuf {
        let runs = dir.join(format!("runs-{host}"));
        let mut found: Vec<PathBuf> = std::fs::read_dir(&runs)
            .map(|rd| rd.flatten().map(|e| e.path()).collect())
            .unwrap_or_default();
        found.sort();
        found
            .pop()
            .unwrap_or_else(|| panic!("no run directory in {}", runs.display()))
    }
}

impl Drop for Hosts {
    fn drop(&mut self) {
        for ns in self.namespaces.iter().rev() {
            ip(&["netns", "del", ns]);
        }
    }
}

/// A host's launcher, its standard error collected as it comes.
pub struct Launcher {
    child: Child,
    err: Arc<Mutex<String>>,
    /// Where the wrapper wrote the launcher's pid.
    pid_file: PathBuf,
}

impl Launcher {
    /// How long [`Launcher::finish`] waits: less than the runner's time limit for these tests.
    pub const PATIENCE: std::time::Duration = std::time::Duration::from_secs(150);

    pub fn start(hosts: &Hosts, host: &str, s: &crate::Scenario) -> Self {
        Self::start_in(hosts, host, s, &s.dir)
    }

    /// As `start`, with its temporary, run and pid files under `dir`.
    pub fn start_in(hosts: &Hosts, host: &str, s: &crate::Scenario, dir: &std::path::Path) -> Self {
        Self::start_file(hosts, host, &s.file, dir, &[])
    }

    /// `caravan launch FILE --host HOST EXTRA…` on `host`, its files under `dir`.
    pub fn start_file(hosts: &Hosts, host: &str, file: &Path, dir: &Path, extra: &[&str]) -> Self {
        std::fs::create_dir_all(dir).unwrap();
        let mut child = hosts.launch(host, file, dir, extra);
        let err = Arc::new(Mutex::new(String::new()));
        let mut pipe = child.stderr.take().unwrap();
        let sink = err.clone();
        std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(n) = pipe.read(&mut buf) {
                if n == 0 {
                    break;
                }
                sink.lock()
                    .unwrap()
                    .push_str(&String::from_utf8_lossy(&buf[..n]));
            }
        });
        let pid_file = dir.join(format!("pid-{host}.txt"));
        Self {
            child,
            err,
            pid_file,
        }
    }

    pub fn stderr(&self) -> String {
        self.err.lock().unwrap().clone()
    }

    /// Waits for the launcher (and its host's listing of /dev/shm) to end. A launcher still
    /// running after [`Launcher::PATIENCE`] is killed and the test fails with its output, so
    /// a hang is reported with what the launcher said, not by the runner's time limit (which
    /// would leave the launcher running).
    pub fn finish(mut self) -> (Option<i32>, String) {
        let started = std::time::Instant::now();
        let status = loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                break status;
            }
            if started.elapsed() > Self::PATIENCE {
                // The launcher (its pid is in the host's folder), then the wrapper.
                let pid = std::fs::read_to_string(&self.pid_file).unwrap_or_default();
                if let Ok(pid) = pid.trim().parse::<i32>() {
                    unsafe { libc::kill(pid, libc::SIGKILL) };
                }
                let _ = self.child.kill();
                let _ = self.child.wait();
                panic!(
                    "a launcher did not end within {:?} (killed); it said:\n{}",
                    Self::PATIENCE,
                    self.stderr()
                );
            }
            std::thread::sleep(std::time::Duration::from_millis(50));
        };
        // The reader thread ends with the pipe; give it the last lines.
        crate::wait_until("the launcher's output is read", || {
            Arc::strong_count(&self.err) == 1
        });
        (status.code(), self.stderr())
    }
}

pub fn pid_of(s: &crate::Scenario, host: &str) -> i32 {
    pid_in(&s.dir, host)
}

/// The pid of `host`'s launcher started with its files under `dir`.
pub fn pid_in(dir: &Path, host: &str) -> i32 {
    std::fs::read_to_string(dir.join(format!("pid-{host}.txt")))
        .unwrap()
        .trim()
        .parse()
        .unwrap()
}

pub fn shm_left(s: &crate::Scenario, host: &str) -> String {
    std::fs::read_to_string(s.dir.join(format!("shm-{host}.txt"))).unwrap_or_default()
}
