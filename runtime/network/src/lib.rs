//! Emulated distribution: virtual hosts, the network links between them and their CPUs.
//!
//! The launcher hands every node the group's [`Network`] (JSON in `CARAVAN_NETWORK`): which
//! host each process runs on, each host's CPU slowdown, and a [`LinkProfile`] for every
//! ordered pair of hosts joined by a link. A subscriber then treats each message by where it
//! came from:
//! - **Same host, or hosts without a link:** delivered as before, zero-copy and immediately.
//! - **Across a link:** copied out of shared memory (as a network would) and delivered
//!   `latency + jitter (+ spike)` after it finished queueing behind earlier messages on the
//!   link (`size / bandwidth` each), or dropped with probability `loss`. Messages of one
//!   publisher stay in order, as on the TCP connections ROS uses.
//!
//! Every draw is a hash of (group seed, publisher, topic, sequence number, subscriber), not a
//! stream of random numbers, so a message's fate does not depend on the order in which
//! subscribers happen to look at messages: lockstep runs stay reproducible with links on.
//! Times are simulated in lockstep (from the message's stamp) and wall-clock in realtime
//! (from its send time).

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The group's hosts and links, as the launcher resolved them from the launch file.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Network {
    pub seed: u64,
    /// Host of every process, by node name.
    pub hosts: BTreeMap<String, String>,
    /// CPU slowdown of the hosts that declare one.
    pub cpu_slowdown: BTreeMap<String, f64>,
    /// Links by ordered host pair (a link between a and b appears as a → b and b → a).
    pub links: Vec<LinkProfile>,
}

/// How the jitter part of a link's delay is distributed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Jitter {
    /// Uniform in [0, jitter].
    #[default]
    Uniform,
    /// |N(0, jitter)|: most messages near the base latency, a tail beyond it.
    Normal,
    /// Exponential with mean `jitter`: a long tail, as queues in a busy access point make.
    Exponential,
}

/// One direction of a link.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LinkProfile {
    pub from: String,
    pub to: String,
    pub latency_ns: u64,
    pub jitter_ns: u64,
    pub jitter: Jitter,
    /// Probability that a message is lost.
    pub loss: f64,
    /// Probability that a message meets a spike (a retransmission burst, a scan for access
    /// points) on top of its delay.
    pub spike_probability: f64,
    /// A spike adds a uniform delay in [min, max], ns.
    pub spike_ns: [u64; 2],
    /// Bits per second; `None` does not limit the rate.
    pub bandwidth_bps: Option<u64>,
}

impl Network {
    /// The `CARAVAN_NETWORK` value, or an empty network when unset.
    pub fn from_json(text: &str) -> Result<Self, String> {
        serde_json::from_str(text).map_err(|e| e.to_string())
    }

    pub fn host_of(&self, node: &str) -> Option<&str> {
        self.hosts.get(node).map(String::as_str)
    }

    /// The link a message takes from host `from` to host `to`, if any.
    pub fn link(&self, from: &str, to: &str) -> Option<&LinkProfile> {
        (from != to)
            .then(|| self.links.iter().find(|l| l.from == from && l.to == to))
            .flatten()
    }

    /// CPU slowdown of `host`, if it declares one.
    pub fn slowdown(&self, host: &str) -> Option<f64> {
        self.cpu_slowdown.get(host).copied()
    }
}

/// What identifies one delivery of one message: the draws depend on these only.
#[derive(Debug, Clone, Copy)]
pub struct MessageId {
    pub seed: u64,
    pub source: u64,
    pub topic: u64,
    pub seq: u64,
    pub subscriber: u64,
}

impl MessageId {
    /// A uniform number in [0, 1) for draw number `k`.
    fn unit(&self, k: u64) -> f64 {
        let mut h = splitmix(self.seed ^ 0x6c69_6e6b);
        for v in [self.source, self.topic, self.seq, self.subscriber, k] {
            h = splitmix(h ^ v);
        }
        (h >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// SplitMix64's finaliser: a well-mixed 64-bit hash step.
fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The sending side of one link as one subscriber sees it: messages queue behind each other.
#[derive(Debug, Clone, Default)]
pub struct LinkQueue {
    /// When the link finishes sending what it already has, ns.
    busy_until_ns: u64,
}

impl LinkProfile {
    /// When a message of `bytes` sent at `sent_ns` arrives, or `None` if it is lost.
    pub fn arrival(
        &self,
        d: &MessageId,
        bytes: usize,
        sent_ns: u64,
        queue: &mut LinkQueue,
    ) -> Option<u64> {
        if d.unit(0) < self.loss {
            return None;
        }
        let transmit_ns = self.bandwidth_bps.map_or(0, |bps| {
            (bytes as u128 * 8 * 1_000_000_000 / bps as u128) as u64
        });
        let start = sent_ns.max(queue.busy_until_ns);
        queue.busy_until_ns = start + transmit_ns;
        let jitter = self.jitter_ns as f64;
        let u = d.unit(1).max(f64::MIN_POSITIVE);
        let jitter_ns = match self.jitter {
            Jitter::Uniform => u * jitter,
            // Box–Muller with a second draw.
            Jitter::Normal => {
                jitter * ((-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * d.unit(2)).cos()).abs()
            }
            Jitter::Exponential => -u.ln() * jitter,
        };
        let spike_ns = if d.unit(3) < self.spike_probability {
            let [lo, hi] = self.spike_ns;
            lo as f64 + d.unit(4) * hi.saturating_sub(lo) as f64
        } else {
            0.0
        };
        Some(queue.busy_until_ns + self.latency_ns + (jitter_ns + spike_ns).round() as u64)
    }
}

/// Deliveries over one link into one node: counts and a latency histogram (0.1 ms bins).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct LinkStats {
    pub from: String,
    pub to: String,
    pub delivered: u64,
    pub dropped: u64,
    /// Latency (arrival − send) in 0.1 ms bins: bin → count.
    pub latency_bins: BTreeMap<u64, u64>,
}

/// Directory of the run where nodes leave their link statistics (`<node>.json`).
pub const LINK_STATS_DIR: &str = "links";

/// Directory of the run where a launcher of a group across machines leaves what it measured of
/// the real network from each other host (`<host>.json`, a list of [`LinkStats`]).
pub const NETWORK_STATS_DIR: &str = "network";

/// Width of a latency bin, ns.
pub const LATENCY_BIN_NS: u64 = 100_000;

impl LinkStats {
    pub fn record(&mut self, latency_ns: Option<u64>) {
        match latency_ns {
            Some(ns) => {
                self.delivered += 1;
                *self.latency_bins.entry(ns / LATENCY_BIN_NS).or_default() += 1;
            }
            None => self.dropped += 1,
        }
    }

    pub fn merge(&mut self, other: &LinkStats) {
        self.delivered += other.delivered;
        self.dropped += other.dropped;
        for (bin, n) in &other.latency_bins {
            *self.latency_bins.entry(*bin).or_default() += n;
        }
    }

    /// The latency at quantile `q` (0..1), ms, from the bins' midpoints.
    pub fn latency_quantile_ms(&self, q: f64) -> Option<f64> {
        let total: u64 = self.latency_bins.values().sum();
        if total == 0 {
            return None;
        }
        let rank = ((q * total as f64).ceil() as u64).clamp(1, total);
        let mut seen = 0;
        for (bin, n) in &self.latency_bins {
            seen += n;
            if seen >= rank {
                return Some((*bin as f64 + 0.5) * LATENCY_BIN_NS as f64 / 1e6);
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn link(loss: f64, jitter: Jitter) -> LinkProfile {
        LinkProfile {
            from: "a".into(),
            to: "b".into(),
            latency_ns: 5_000_000,
            jitter_ns: 2_000_000,
            jitter,
            loss,
            spike_probability: 0.0,
            spike_ns: [0, 0],
            bandwidth_bps: None,
        }
    }

    fn deliveries(n: u64) -> impl DoubleEndedIterator<Item = MessageId> {
        (0..n).map(|seq| MessageId {
            seed: 7,
            source: 11,
            topic: 13,
            seq,
            subscriber: 17,
        })
    }

    /// Mean and standard deviation of the delays of `n` messages sent at t = 0, and the
    /// fraction lost (no queueing: each message has the link to itself).
    fn sample(l: &LinkProfile, n: u64) -> (f64, f64, f64) {
        let delays: Vec<f64> = deliveries(n)
            .filter_map(|d| l.arrival(&d, 100, 0, &mut LinkQueue::default()))
            .map(|t| t as f64)
            .collect();
        let mean = delays.iter().sum::<f64>() / delays.len() as f64;
        let var = delays.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / delays.len() as f64;
        (mean, var.sqrt(), 1.0 - delays.len() as f64 / n as f64)
    }

    #[test]
    fn delay_and_loss_match_the_profile_within_sampling_error() {
        let n = 100_000;
        // Uniform jitter in [0, 2 ms]: mean 5 + 1 ms, σ 2/√12 ms.
        let (mean, sd, lost) = sample(&link(0.05, Jitter::Uniform), n);
        assert!((mean - 6.0e6).abs() < 0.02e6, "mean {mean}");
        assert!((sd - 2.0e6 / 12f64.sqrt()).abs() < 0.02e6, "sd {sd}");
        // Loss 5 %: the binomial σ is 0.07 %; allow 5 σ.
        assert!((lost - 0.05).abs() < 0.0035, "lost {lost}");
        // |N(0, 2 ms)|: mean 2·√(2/π) ms.
        let (mean, _, lost) = sample(&link(0.0, Jitter::Normal), n);
        assert!((mean - (5.0e6 + 2.0e6 * (2.0 / std::f64::consts::PI).sqrt())).abs() < 0.03e6);
        assert_eq!(lost, 0.0);
        // Exponential, mean 2 ms and σ 2 ms.
        let (mean, sd, _) = sample(&link(0.0, Jitter::Exponential), n);
        assert!((mean - 7.0e6).abs() < 0.04e6, "mean {mean}");
        assert!((sd - 2.0e6).abs() < 0.05e6, "sd {sd}");
    }

    #[test]
    fn no_message_arrives_before_its_latency_and_queues_respect_bandwidth() {
        let mut l = link(0.0, Jitter::Uniform);
        for d in deliveries(1000) {
            let t = l
                .arrival(&d, 100, 1_000, &mut LinkQueue::default())
                .unwrap();
            assert!(t >= 1_000 + l.latency_ns);
        }
        // 1 Mbit/s: 12,500 B take 100 ms each; three sent together leave 100 ms apart.
        l.bandwidth_bps = Some(1_000_000);
        l.jitter_ns = 0;
        let mut q = LinkQueue::default();
        let arrivals: Vec<u64> = deliveries(3)
            .map(|d| l.arrival(&d, 12_500, 0, &mut q).unwrap())
            .collect();
        assert_eq!(arrivals, [105_000_000, 205_000_000, 305_000_000]);
    }

    #[test]
    fn draws_depend_only_on_the_message() {
        let l = link(0.3, Jitter::Normal);
        let a: Vec<_> = deliveries(100)
            .map(|d| l.arrival(&d, 10, 0, &mut LinkQueue::default()))
            .collect();
        let b: Vec<_> = deliveries(100)
            .rev()
            .map(|d| l.arrival(&d, 10, 0, &mut LinkQueue::default()))
            .collect::<Vec<_>>()
            .into_iter()
            .rev()
            .collect();
        assert_eq!(a, b);
    }

    #[test]
    fn stats_give_quantiles_from_bins() {
        let mut s = LinkStats::default();
        for ms in 1..=100u64 {
            s.record(Some(ms * 1_000_000));
        }
        s.record(None);
        assert_eq!((s.delivered, s.dropped), (100, 1));
        assert!((s.latency_quantile_ms(0.5).unwrap() - 50.05).abs() < 1e-9);
        assert!((s.latency_quantile_ms(0.99).unwrap() - 99.05).abs() < 1e-9);
    }
}

/// One node's view of the network: the links into its host, by publisher.
#[derive(Debug)]
pub struct NodeNet {
    pub seed: u64,
    pub node_hash: u64,
    /// Links into this node's host.
    pub links: Vec<LinkProfile>,
    /// Publisher node hash → index into `links`, for publishers on linked hosts.
    pub inbound: Vec<(u64, usize)>,
    /// Per link: what this node's subscribers received over it.
    pub stats: std::cell::RefCell<Vec<LinkStats>>,
    /// This host's CPU slowdown, if declared.
    pub slowdown: Option<f64>,
}

impl NodeNet {
    /// `None` when the node's host has no links in and no CPU slowdown: nothing to emulate.
    pub fn new(network: &Network, node: &str, host: &str) -> Option<Self> {
        let links: Vec<LinkProfile> = network
            .links
            .iter()
            .filter(|l| l.to == host && l.from != host)
            .cloned()
            .collect();
        let inbound = network
            .hosts
            .iter()
            .filter_map(|(name, from)| {
                let i = links.iter().position(|l| &l.from == from)?;
                Some((caravan_schemas::lockstep::name_hash(name), i))
            })
            .collect();
        let slowdown = network.slowdown(host);
        if links.is_empty() && slowdown.is_none() {
            return None;
        }
        let stats = links
            .iter()
            .map(|l| LinkStats {
                from: l.from.clone(),
                to: l.to.clone(),
                ..Default::default()
            })
            .collect();
        Some(Self {
            seed: network.seed,
            node_hash: caravan_schemas::lockstep::name_hash(node),
            links,
            inbound,
            stats: std::cell::RefCell::new(stats),
            slowdown,
        })
    }

    /// The link index messages of publisher `source` come over, if any.
    pub fn link_of(&self, source: u64) -> Option<usize> {
        self.inbound
            .iter()
            .find(|(s, _)| *s == source)
            .map(|(_, i)| *i)
    }
}
