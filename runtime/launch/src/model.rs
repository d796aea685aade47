//! What a launch file says, once parsed and validated. Every field holds its default when the
//! file left it out, so the launcher never needs to know the defaults.

use caravan::ClockMode;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::str::FromStr;
use std::time::Duration;

/// A validated launch file.
#[derive(Debug, Clone, PartialEq)]
pub struct LaunchFile {
    /// The file as named on the command line.
    pub path: PathBuf,
    pub group: GroupSpec,
    pub hosts: BTreeMap<String, HostSpec>,
    pub links: Vec<LinkSpec>,
    pub processes: Vec<ProcessSpec>,
    /// The `[[report]]` entries, in file order (included files' first).
    pub reports: Vec<ReportSpec>,
    /// The file after includes, templates, arguments and `--set` overrides; the launcher saves
    /// it in the run directory so a run can be repeated exactly. It names executables and
    /// paths as written, so an included file's relative paths stay relative to its directory.
    pub resolved_toml: String,
    /// Processes the file declares but this run leaves out (`caravan launch --only`), by name,
    /// with their hosts: a recording played in their place still crosses the emulated links
    /// from where they ran.
    pub left_out: BTreeMap<String, String>,
}

/// The `[group]` table.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupSpec {
    pub name: String,
    pub clock: ClockMode,
    /// How long the group runs; `None` runs until stopped.
    pub duration: Option<Duration>,
    pub seed: u64,
    /// The base tick of simulated time.
    pub tick: Duration,
    /// Lockstep: nodes due one tick later may start while the earlier time still runs, when
    /// they share no topic with its unfinished nodes (`caravan::lockstep`). Off, every time
    /// waits for the one before; recordings are the same bytes either way.
    pub overlap: bool,
    /// Lockstep: a periodic node is granted several periods at once when no node publishing
    /// to its inputs can step meanwhile (`caravan_lockstep`, "batches"): it wakes once for
    /// them. Off, every step is granted alone; recordings are the same bytes either way.
    pub batch: bool,
    /// Topic patterns to record (see [`glob_match`]).
    pub record: Vec<String>,
    /// Time between SIGTERM and SIGKILL when stopping a process.
    pub grace: Duration,
    /// Lockstep: wall time a node may take for one step before it is deemed hung and killed.
    pub step_timeout: Duration,
    /// Lockstep: wall time every process has, from its start, to join the schedule; the group
    /// fails when one has not (a program that never joins would stall it forever).
    pub join_timeout: Duration,
    /// Across machines: how long a host's connections may stay silent before the other
    /// hosts take it for gone (zenoh's lease; keep-alives go out four times per lease). A
    /// host that exits or is killed closes its connections and is noticed at once; this
    /// bounds only silence (a cable, power, a machine paused or starved of CPU).
    /// [`GroupSpec::MIN_HOST_LEASE`] to [`GroupSpec::MAX_HOST_LEASE`].
    pub host_lease: Duration,
    /// How long each node, and the lockstep scheduler, spins for its next message, grant or
    /// report before it sleeps ([`caravan::spin`]); a process's own `spin` overrides it. Zero,
    /// the default, sleeps at once.
    pub spin: Duration,
}

impl GroupSpec {
    pub const DEFAULT_TICK: Duration = Duration::from_millis(1);
    pub const DEFAULT_GRACE: Duration = Duration::from_secs(3);
    pub const DEFAULT_STEP_TIMEOUT: Duration = Duration::from_secs(30);
    pub const DEFAULT_JOIN_TIMEOUT: Duration = Duration::from_secs(60);
    /// zenoh's own default. A loaded two-core machine can stall a launcher for over a second
    /// (the 1 s lease Caravan used before failed 4 of ~30 three-host starts under load).
    pub const DEFAULT_HOST_LEASE: Duration = Duration::from_secs(10);
    /// Below this a scheduler hiccup passes for a lost host.
    pub const MIN_HOST_LEASE: Duration = Duration::from_millis(500);
    /// A lost host should not hold the group for longer than this.
    pub const MAX_HOST_LEASE: Duration = Duration::from_secs(600);
}

/// One entry of `[hosts]`.
#[derive(Debug, Clone, PartialEq)]
pub struct HostSpec {
    /// How many times slower than this machine the host's CPU is (1.0 = as fast). When set,
    /// lockstep delays each output of the host's nodes by their compute time times it; when
    /// absent, computing takes no simulated time.
    pub cpu_slowdown: Option<f64>,
    /// Zenoh endpoints (`tcp/ADDRESS:PORT`) this host's launcher listens on when the group
    /// runs on several machines (`caravan launch --host`); other hosts connect to them.
    pub listen: Vec<String>,
    /// Zenoh endpoints this host's launcher dials: other hosts' `listen` endpoints.
    pub connect: Vec<String>,
    /// Across machines: the group starts only once this host joined, and stops when it
    /// leaves. A host that is not required may join late or leave; the others go on.
    pub required: bool,
    /// TLS for this host's connections, over QUIC (endpoints `quic/…`), with both sides'
    /// certificates checked: a launcher joins only with a certificate signed by the group's
    /// authority.
    pub tls: Option<TlsSpec>,
    /// Lockstep across machines: this host's launcher owns simulated time (runs the
    /// scheduler) and records the whole group. At most one host says so; when none does, the
    /// only host that listens is the one.
    pub clock: bool,
}

impl Default for HostSpec {
    fn default() -> Self {
        Self {
            cpu_slowdown: None,
            listen: Vec::new(),
            connect: Vec::new(),
            required: true,
            tls: None,
            clock: false,
        }
    }
}

/// A host's `tls` table: PEM files, relative to the file that names them.
#[derive(Debug, Clone, PartialEq)]
pub struct TlsSpec {
    /// The group's certificate authority: the other hosts' certificates must be signed by it.
    pub ca: PathBuf,
    /// This host's certificate, shown to the others (as server and as client).
    pub certificate: PathBuf,
    /// Its private key.
    pub key: PathBuf,
    /// Which of the three files do not exist here, each as a problem naming file, line and
    /// key. Only the host itself needs them: `--host` refuses to start its own host with any
    /// missing, and ignores the other hosts' (their keys stay on their machines).
    pub missing: Vec<String>,
}

/// One `[[links]]` entry: the network between two sets of hosts.
#[derive(Debug, Clone, PartialEq)]
pub struct LinkSpec {
    /// Two host patterns (see [`glob_match`]), each matching at least one declared host.
    pub between: [String; 2],
    pub latency: Duration,
    pub jitter: Duration,
    /// How the jitter is distributed.
    pub distribution: caravan::network::Jitter,
    /// Probability of losing a message, 0.0 to 1.0.
    pub loss: f64,
    /// Probability that a message meets a delay spike, 0.0 to 1.0.
    pub spike_probability: f64,
    /// The extra delay of a spike, uniform between the two.
    pub spike: [Duration; 2],
    pub bandwidth_bps: Option<u64>,
}

/// What to do when a process exits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Restart {
    #[default]
    Never,
    OnFailure,
    Always,
}

impl Restart {
    pub const NAMES: [&'static str; 3] = ["never", "on-failure", "always"];

    pub fn as_str(self) -> &'static str {
        match self {
            Restart::Never => "never",
            Restart::OnFailure => "on-failure",
            Restart::Always => "always",
        }
    }
}

impl std::fmt::Display for Restart {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for Restart {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "never" => Ok(Restart::Never),
            "on-failure" => Ok(Restart::OnFailure),
            "always" => Ok(Restart::Always),
            other => Err(format!(
                "'{other}' is not a restart policy; expected 'never', 'on-failure' or 'always'"
            )),
        }
    }
}

/// How to start a process.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Exec {
    /// A single bare program name that `resolve_exec` found: a workspace binary (checked
    /// first by the caller) or a program on PATH. Resolve it again when starting.
    Workspace(String),
    /// A command line split with shell quoting: program and its arguments. A program containing
    /// '/' is a path, relative to the launch file's directory unless absolute; a bare program
    /// name is resolved like `Workspace`.
    Command(Vec<String>),
}

/// One `[[process]]` entry.
#[derive(Debug, Clone, PartialEq)]
pub struct ProcessSpec {
    pub name: String,
    pub exec: Exec,
    /// Extra arguments appended after those of `exec`.
    pub args: Vec<String>,
    /// Where the process runs; "localhost" unless the file says otherwise.
    pub host: String,
    /// The rate as written (validated with `caravan::parse_rate`).
    pub rate: Option<String>,
    /// The topic whose messages trigger a step.
    pub on: Option<String>,
    /// How long the node spins for its next message or grant before it sleeps
    /// ([`caravan::spin`]); `None`: the group's `spin`.
    pub spin: Option<Duration>,
    /// Free-form parameters; always a JSON object.
    pub params: serde_json::Value,
    pub restart: Restart,
    pub restart_backoff: Duration,
    pub max_restarts: u32,
    /// Whether the group stops when this process fails for good.
    pub required: bool,
    /// Whether the group stops when this process exits at all (an exit 0 then completes the
    /// run): a process that knows when the experiment is over, such as an episode counter.
    pub ends_group: bool,
    pub env: BTreeMap<String, String>,
    /// Whether the launcher runs the program once with `CARAVAN_CHECK=1` before the group
    /// starts, to check its params and inputs; `None` does so for Caravan's own programs
    /// (workspace binaries and `caravan-python` agents), which all understand it.
    pub check: Option<bool>,
    /// The container this node runs in (in lockstep): nodes of one program with the same
    /// `container` run in one process, stepped by one thread (`caravan::container`).
    pub container: Option<String>,
    /// The directory of the launch file that defined the process, absolute: relative `exec`
    /// paths start there, and the process gets it as `CARAVAN_LAUNCH_DIR`.
    pub launch_dir: PathBuf,
}

/// The list of the launch file an entry belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EntryList {
    /// `[[process]]`: [`LaunchFile::processes`].
    Process,
    /// `[[report]]`: [`LaunchFile::reports`].
    Report,
}

impl EntryList {
    /// The list's key in the file.
    pub fn key(self) -> &'static str {
        match self {
            EntryList::Process => "process",
            EntryList::Report => "report",
        }
    }
}

/// What a process's check (`CARAVAN_CHECK=1`) or a report plugin's (`--check`) found wrong
/// with its input, before the group started.
#[derive(Debug, Clone, PartialEq)]
pub struct EntryProblem {
    /// Whether the entry is a process or a report plugin.
    pub list: EntryList,
    /// Index of the entry in its list.
    pub index: usize,
    /// The params key the message names (dotted, as `poses[0].x`), when it names one.
    pub key: Option<String>,
    pub message: String,
}

/// One `[[report]]` entry: an executable that computes report sections after the run.
#[derive(Debug, Clone, PartialEq)]
pub struct ReportSpec {
    pub exec: Exec,
    /// Free-form parameters; always a JSON object.
    pub params: serde_json::Value,
    /// How long the plugin may run on a run directory before it is killed and reported as
    /// failed (`timeout`, default [`ReportSpec::DEFAULT_TIMEOUT`]).
    pub timeout: Duration,
    /// The directory of the launch file that defined the entry, absolute.
    pub launch_dir: PathBuf,
}

impl ReportSpec {
    /// Ten minutes: generous for a program that reads one run's recording and writes a
    /// section; a plugin past it is stuck (as one plotting an axis of 1e308 was), not busy.
    pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(600);
    /// A day: more is a typo.
    pub const MAX_TIMEOUT: Duration = Duration::from_secs(86_400);
}

impl ProcessSpec {
    pub const DEFAULT_HOST: &'static str = "localhost";
    pub const DEFAULT_BACKOFF: Duration = Duration::from_millis(500);
    pub const DEFAULT_MAX_RESTARTS: u32 = 3;
}

pub use caravan::pattern::glob_match;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn launch_restart_names_round_trip() {
        for name in Restart::NAMES {
            assert_eq!(name.parse::<Restart>().unwrap().to_string(), name);
        }
        assert!("sometimes".parse::<Restart>().is_err());
    }
}
