//! One group on many machines: each machine runs `caravan launch FILE --host NAME`, which
//! starts that host's processes and joins the other hosts' launchers over zenoh.
//!
//! Each launcher opens one zenoh peer session at its host's `listen` / `connect` endpoints
//! (multicast scouting off; gossip on, so hosts that connected to one hub also find each
//! other). Over it the launchers
//! - say who is up and who has finished ([`presence`]): the group starts once every required
//!   host joined, ends when every host's processes have exited, and stops everywhere when one
//!   host stops it or a required host leaves;
//! - carry topics between hosts ([`relay`]): a topic read on one host and published on
//!   another is an iceoryx2 zero-copy topic on each, and crosses between them over zenoh with
//!   its header.
//!
//! Everything is said under the group's own keys ([`keys`]).

pub mod causal;
mod context;
pub mod handshake;
mod inbound;
pub mod keys;
mod outbound;
pub mod presence;
pub mod relay;
mod types;

use anyhow::{Result, anyhow, bail};
use caravan_launch::model::{HostSpec, LaunchFile};
use keys::StopNotice;
use presence::{Change, Presence};
use std::collections::BTreeSet;
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};
use zenoh::Wait;
use zenoh::sample::SampleKind;

/// What the other hosts tell the launcher while the group runs.
#[derive(Debug, Clone, PartialEq)]
pub enum FleetEvent {
    /// A host left before its processes finished.
    Left { host: String, required: bool },
    /// Another host stopped the group.
    Stopped(StopNotice),
    /// Every host's processes have exited.
    AllDone,
    /// Topics could not cross between hosts, or another launcher of this host came first.
    Failed(String),
}

/// zenoh's errors are boxed trait objects; make them anyhow errors.
pub fn z<T>(r: zenoh::Result<T>) -> Result<T> {
    r.map_err(|e| anyhow!("zenoh: {e}"))
}

/// Checks that the group can run its part on `host`: the host is declared, and it can reach
/// the others.
pub fn check_host(lf: &LaunchFile, host: &str) -> Result<()> {
    let file = lf.path.display();
    if !lf.hosts.contains_key(host) {
        let names: Vec<&str> = lf.hosts.keys().map(String::as_str).collect();
        if names.is_empty() {
            bail!("--host {host}: {file} has no [hosts] table; declare the hosts there");
        }
        let hint = caravan_launch::suggest::hint(host, &names);
        bail!("--host {host}: {file} declares no host '{host}' under [hosts]{hint}");
    }
    // Only this host's own files: the others' keys stay on their machines.
    if let Some(tls) = &lf.hosts[host].tls
        && !tls.missing.is_empty()
    {
        bail!(
            "--host {host}: this machine lacks host '{host}''s tls files (each host needs its own ca, certificate and key, and no other host's):\n  {}",
            tls.missing.join("\n  ")
        );
    }
    if lf.group.clock == caravan::ClockMode::Lockstep {
        clock_host(lf)?;
        // The scheduler would wait for its processes, and cannot learn of their exits.
        if let Some((name, _)) = lf.hosts.iter().find(|(_, h)| !h.required) {
            bail!(
                "--host {host}: {file} runs in lockstep, where every host is required (host '{name}' has required = false); run it with --clock realtime, or make the host required"
            );
        }
    }
    let reachable = lf.hosts.values().any(|h| !h.listen.is_empty());
    if lf.hosts.len() > 1 && !reachable {
        bail!(
            "--host {host}: no host of {file} has `listen` endpoints, so the hosts cannot find each other; give one host listen = [\"tcp/ADDRESS:PORT\"] and the others connect = [the same]"
        );
    }
    Ok(())
}

/// In a lockstep group across hosts, the host whose launcher runs the scheduler and records:
/// the one marked `clock = true`, or else the only host that listens (the hub the others
/// connect to).
pub fn clock_host(lf: &LaunchFile) -> Result<String> {
    if let Some((name, _)) = lf.hosts.iter().find(|(_, h)| h.clock) {
        return Ok(name.clone());
    }
    let listening: Vec<&String> = lf
        .hosts
        .iter()
        .filter(|(_, h)| !h.listen.is_empty())
        .map(|(name, _)| name)
        .collect();
    match listening.as_slice() {
        [one] => Ok(one.to_string()),
        _ => bail!(
            "{}: a lockstep group across hosts needs one host to own simulated time and record; mark it with clock = true under its [hosts.NAME] table",
            lf.path.display()
        ),
    }
}

/// The zenoh session of a host described by `spec`, in a group whose hosts are taken for gone
/// after `lease` of silence (`group.host_lease`).
pub fn session_config(spec: &HostSpec, lease: Duration) -> Result<zenoh::Config> {
    let list = |v: &[String]| serde_json::to_string(v).expect("strings serialise");
    let mut c = zenoh::Config::default();
    let mut set = |key: &str, value: &str| z(c.insert_json5(key, value));
    set("mode", r#""peer""#)?;
    // Only the endpoints of the launch file, and hosts those tell of (gossip).
    set("scouting/multicast/enabled", "false")?;
    set(
        "scouting/gossip/autoconnect_strategy",
        r#"{ peer: { to_router: "always", to_peer: "greater-zid" } }"#,
    )?;
    if !spec.listen.is_empty() {
        set("listen/endpoints", &list(&spec.listen))?;
    }
    if let Some(tls) = &spec.tls {
        let path = |p: &std::path::Path| {
            serde_json::to_string(&p.display().to_string()).expect("a string serialises")
        };
        // Only QUIC (TLS 1.3), certificates checked both ways: a launcher without a
        // certificate of the group's authority is refused, and refuses. Not zenoh's tls/
        // link: see `launch::convert::TLS_LINK_REFUSED`.
        set("transport/link/protocols", r#"["quic"]"#)?;
        if spec.listen.is_empty() {
            set("listen/endpoints", r#"["quic/[::]:0"]"#)?;
        }
        set("transport/link/tls/root_ca_certificate", &path(&tls.ca))?;
        for side in ["listen", "connect"] {
            set(
                &format!("transport/link/tls/{side}_certificate"),
                &path(&tls.certificate),
            )?;
            set(
                &format!("transport/link/tls/{side}_private_key"),
                &path(&tls.key),
            )?;
        }
        set("transport/link/tls/enable_mtls", "true")?;
    }
    set("connect/endpoints", &list(&spec.connect))?;
    // Bytes cross the network even between "hosts" on one machine.
    set("transport/shared_memory/enabled", "false")?;
    // A host gone without closing its connections (power, cable) is noticed within a lease;
    // one that exits or is killed closes them and is noticed at once.
    set("transport/link/tx/lease", &lease.as_millis().to_string())?;
    set("transport/link/tx/keep_alive", "4")?;
    Ok(c)
}

/// What the zenoh callbacks and the launcher share.
struct Shared {
    presence: Mutex<Presence>,
    changed: Condvar,
    /// Where events go once the group runs; until then they wait here.
    events: Mutex<Outbox>,
    /// Why this launcher must not run: another launcher of its host came first.
    conflict: Mutex<Option<String>>,
    /// TLS handshakes that failed, each once, in the order seen.
    handshakes: Mutex<Vec<handshake::Failure>>,
    /// The signal that stopped the wait for the other hosts.
    interrupted: Mutex<Option<i32>>,
}

/// Ends [`Bridge::wait_for_hosts`] early, from another thread (a signal handler's).
pub struct Interrupter(Arc<Shared>);

impl Interrupter {
    pub fn interrupt(&self, signal: i32) {
        // Under the lock the join wait holds: it cannot miss this.
        let _presence = self.0.presence.lock().unwrap();
        *self.0.interrupted.lock().unwrap() = Some(signal);
        self.0.changed.notify_all();
    }
}

/// Why [`Bridge::wait_for_hosts`] gave up: a signal (Ctrl-C, SIGTERM) came first.
#[derive(Debug)]
pub struct Interrupted(pub i32);

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "stopped by signal {} while waiting for the other hosts; nothing was started",
            self.0
        )
    }
}

impl std::error::Error for Interrupted {}

/// Where the bridge's events go: the launcher's main loop, in the launcher's own event type.
pub type Notify = Box<dyn Fn(FleetEvent) + Send>;

#[derive(Default)]
struct Outbox {
    to: Option<Notify>,
    waiting: Vec<FleetEvent>,
}

impl Shared {
    fn tell(&self, event: FleetEvent) {
        let mut out = self.events.lock().unwrap();
        match &out.to {
            Some(notify) => notify(event),
            None => out.waiting.push(event),
        }
    }

    /// Another launcher runs this host and started first: this one gives way.
    fn give_way(&self, why: String) {
        let presence = self.presence.lock().unwrap();
        let mut conflict = self.conflict.lock().unwrap();
        if conflict.is_none() {
            *conflict = Some(why.clone());
            self.tell(FleetEvent::Failed(why));
        }
        drop(conflict);
        // Under the lock the join wait holds: it cannot miss this.
        self.changed.notify_all();
        drop(presence);
    }

    fn apply(&self, changes: impl IntoIterator<Item = Change>) {
        self.changed.notify_all();
        for change in changes {
            match change {
                Change::Left { host, required } => self.tell(FleetEvent::Left { host, required }),
                Change::AllDone => self.tell(FleetEvent::AllDone),
            }
        }
    }
}

/// This host's link to the rest of the group.
pub struct Bridge {
    group: String,
    host: String,
    session: zenoh::Session,
    shared: Arc<Shared>,
    _watchers: Vec<zenoh::pubsub::Subscriber<()>>,
    _token: zenoh::liveliness::LivelinessToken,
    done_token: Mutex<Option<zenoh::liveliness::LivelinessToken>>,
    relay: Option<relay::Relay>,
}

impl Bridge {
    /// Opens this host's session and says it is up.
    pub fn open(lf: &LaunchFile, host: &str) -> Result<Self> {
        let group = lf.group.name.clone();
        let spec = &lf.hosts[host];
        let session = z(zenoh::open(session_config(spec, lf.group.host_lease)?).wait())
            .map_err(|e| anyhow!("host '{host}': cannot open its zenoh session: {e}"))?;
        let shared = Arc::new(Shared {
            presence: Mutex::new(Presence::new(
                lf.hosts
                    .iter()
                    .map(|(name, h)| (name.clone(), h.required))
                    .collect(),
            )),
            changed: Condvar::new(),
            events: Mutex::new(Outbox::default()),
            conflict: Mutex::new(None),
            handshakes: Mutex::new(Vec::new()),
            interrupted: Mutex::new(None),
        });
        if spec.tls.is_some() {
            let (shared, hosts) = (shared.clone(), lf.hosts.clone());
            caravan::log::tap(Box::new(move |target, message| {
                if let Some(failure) = handshake::parse(&hosts, target, message) {
                    let mut seen = shared.handshakes.lock().unwrap();
                    if !seen.contains(&failure) {
                        seen.push(failure);
                        drop(seen);
                        // Under the lock the join wait holds: it cannot miss this.
                        let _presence = shared.presence.lock().unwrap();
                        shared.changed.notify_all();
                    }
                }
            }));
        }
        shared.presence.lock().unwrap().joined(host);
        let me_id = keys::LauncherId {
            start_ns: caravan::wall_clock_ns(),
            zid: session.zid().to_string(),
        };
        let watch = |kind: &'static str| -> Result<zenoh::pubsub::Subscriber<()>> {
            let shared = shared.clone();
            let me = host.to_string();
            let me_id = me_id.clone();
            let pattern = match kind {
                "host" => keys::host(&group, "*", "*"),
                _ => keys::done(&group, "*"),
            };
            z(session
                .liveliness()
                .declare_subscriber(pattern)
                .history(true)
                .callback(move |sample| {
                    let key = sample.key_expr().as_str();
                    let (h, id) = match kind {
                        "host" => match keys::host_of(key) {
                            Some((h, id)) => (h, Some(id)),
                            None => return,
                        },
                        _ => (keys::last(key), None),
                    };
                    if h == me {
                        // Another launcher of this host?
                        if let Some(other) = id.filter(|id| *id != me_id)
                            && sample.kind() == SampleKind::Put
                        {
                            on_twin(&shared, &me_id, &other, &me);
                        }
                        return;
                    }
                    let mut p = shared.presence.lock().unwrap();
                    if !p.knows(h) {
                        return;
                    }
                    let zid = id.map(|id| id.zid).unwrap_or_default();
                    let change: Vec<Change> = match (kind, sample.kind()) {
                        ("host", SampleKind::Put) => p.launcher_up(h, &zid).into_iter().collect(),
                        ("host", SampleKind::Delete) => p.launcher_down(h, &zid),
                        ("done", SampleKind::Put) => p.finished(h).into_iter().collect(),
                        _ => Vec::new(),
                    };
                    drop(p);
                    shared.apply(change);
                })
                .wait())
        };
        let mut watchers = vec![watch("host")?, watch("done")?];
        let stops = {
            let shared = shared.clone();
            let me = host.to_string();
            z(session
                .declare_subscriber(keys::stop(&group))
                .callback(move |sample| {
                    let notice = serde_json::from_slice::<StopNotice>(&sample.payload().to_bytes());
                    if let Ok(notice) = notice
                        && notice.host != me
                    {
                        shared.tell(FleetEvent::Stopped(notice));
                    }
                })
                .wait())?
        };
        watchers.push(stops);
        let token = z(session
            .liveliness()
            .declare_token(keys::host(&group, host, &me_id.key_chunk()))
            .wait())?;
        Ok(Self {
            group,
            host: host.to_string(),
            session,
            shared,
            _watchers: watchers,
            _token: token,
            done_token: Mutex::new(None),
            relay: None,
        })
    }

    /// The host this launcher runs.
    pub fn host(&self) -> &str {
        &self.host
    }

    /// What ends [`Bridge::wait_for_hosts`] early.
    pub fn interrupter(&self) -> Interrupter {
        Interrupter(self.shared.clone())
    }

    /// Waits until every required host has joined; an error names those that did not, or is
    /// [`Interrupted`].
    pub fn wait_for_hosts(&self, timeout: Duration, say: impl Fn(&str)) -> Result<()> {
        let deadline = Instant::now() + timeout;
        let mut presence = self.shared.presence.lock().unwrap();
        let mut said = false;
        let mut told = 0;
        loop {
            let missing = presence.missing();
            let failures = self.shared.handshakes.lock().unwrap().clone();
            for failure in &failures[told..] {
                say(&failure.describe(&missing));
            }
            told = failures.len();
            if let Some(signal) = *self.shared.interrupted.lock().unwrap() {
                return Err(Interrupted(signal).into());
            }
            if let Some(why) = self.shared.conflict.lock().unwrap().clone() {
                bail!("{why}");
            }
            let lost = presence.lost();
            if !lost.is_empty() {
                bail!(
                    "required host(s) {} left before the group started",
                    quoted(&lost)
                );
            }
            if missing.is_empty() {
                return Ok(());
            }
            let now = Instant::now();
            if now >= deadline {
                let why = match failures.as_slice() {
                    [] => "start `caravan launch FILE --host NAME` on each, and check their [hosts] listen / connect endpoints".to_string(),
                    seen => seen
                        .iter()
                        .map(|f| f.describe(&missing))
                        .collect::<Vec<_>>()
                        .join("; "),
                };
                bail!(
                    "host(s) {} did not join within {timeout:?} (group.join_timeout): {why}",
                    quoted(&missing)
                );
            }
            if !said {
                say(&format!("waiting for host(s) {} to join", quoted(&missing)));
                said = true;
            }
            presence = self
                .shared
                .changed
                .wait_timeout(presence, deadline - now)
                .unwrap()
                .0;
        }
    }

    /// From now on, reports what the other hosts do to `events`, and carries topics between
    /// this host's processes (group config `iceoryx`) and the other hosts'.
    pub fn attach(
        &mut self,
        events: Notify,
        iceoryx: &iceoryx2::config::Config,
        remote_nodes: BTreeSet<u64>,
        clock_host: Option<String>,
        run_dir: &std::path::Path,
    ) -> Result<()> {
        {
            let mut out = self.shared.events.lock().unwrap();
            for event in out.waiting.drain(..) {
                events(event);
            }
            out.to = Some(events);
        }
        let shared = self.shared.clone();
        let cfg = relay::RelayConfig {
            group: self.group.clone(),
            host: self.host.clone(),
            iceoryx: iceoryx.clone(),
            remote: remote_nodes,
            clock_host,
            stats_dir: run_dir.join(caravan::network::NETWORK_STATS_DIR),
        };
        self.relay = Some(relay::Relay::start(
            self.session.clone(),
            cfg,
            move |why| shared.tell(FleetEvent::Failed(why)),
        )?);
        Ok(())
    }

    /// Whether another launcher of this host came first, and this one gave way.
    fn gave_way(&self) -> bool {
        self.shared.conflict.lock().unwrap().is_some()
    }

    /// Every process of this host has exited: the group ends once every host's have.
    pub fn local_done(&self) {
        let mut token = self.done_token.lock().unwrap();
        if token.is_none() && !self.gave_way() {
            *token = z(self
                .session
                .liveliness()
                .declare_token(keys::done(&self.group, &self.host))
                .wait())
            .ok();
            let change = self.shared.presence.lock().unwrap().finished(&self.host);
            self.shared.apply(change);
        }
    }

    /// Tells the other hosts this host stopped the group, and why.
    pub fn stop(&self, outcome: &str, failure: Option<&str>) {
        // A launcher that gave way to another of its host stops itself only.
        if self.gave_way() {
            return;
        }
        let notice = StopNotice {
            host: self.host.clone(),
            outcome: outcome.to_string(),
            failure: failure.map(str::to_string),
        };
        let payload = serde_json::to_vec(&notice).expect("a notice serialises");
        // Never dropped under congestion, and ahead of the topics' data (zenoh's default
        // for a put is to drop it when the link is busy).
        let _ = self
            .session
            .put(keys::stop(&self.group), payload)
            .congestion_control(zenoh::qos::CongestionControl::Block)
            .priority(zenoh::qos::Priority::RealTime)
            .wait();
    }

    /// Stops carrying topics and closes the session (others see this host leave).
    pub fn close(mut self) {
        if let Some(relay) = self.relay.take() {
            relay.stop();
        }
        let _ = self.session.close().wait();
    }
}

/// Another launcher of this launcher's host (`host`) is up. The one that started later gives
/// way (its group fails with a message naming the other); the earlier one warns and goes on.
fn on_twin(shared: &Shared, me: &keys::LauncherId, other: &keys::LauncherId, host: &str) {
    if other < me {
        shared.give_way(format!(
            "another launcher already runs host '{host}' of this group (zenoh id {}); start one launcher per host",
            other.zid
        ));
    } else {
        eprintln!(
            "caravan: warning: a second launcher for host '{host}' joined (zenoh id {}); it gives way",
            other.zid
        );
    }
}

fn quoted(names: &[String]) -> String {
    names
        .iter()
        .map(|n| format!("'{n}'"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The node ids (header `source_id`) of the processes other hosts run: their messages reach
/// this host through the bridge and must not be sent back.
pub fn remote_nodes(lf: &LaunchFile) -> BTreeSet<u64> {
    lf.left_out
        .keys()
        .map(|name| caravan::schemas::lockstep::name_hash(name))
        .collect()
}
