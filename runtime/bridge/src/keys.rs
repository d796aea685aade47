//! The zenoh key space of a group: everything a group says between hosts lives under
//! `caravan/GROUP/`, so two groups on one network never hear each other.
//!
//! - `caravan/G/host/H/START-ZID`: liveliness token, a launcher of host H is up, started at
//!   START (wall clock, ns) with zenoh id ZID ([`LauncherId`]): two launchers of one host see
//!   each other, and the later gives way;
//! - `caravan/G/done/H`: liveliness token, every process of host H has exited;
//! - `caravan/G/stop`: a put, a host stopped the group (JSON [`StopNotice`]);
//! - `caravan/G/want/H/TYPE/CONTRACT/TOPIC`: liveliness token, a process of host H reads
//!   TOPIC, of message type TYPE with delivery CONTRACT (`lossless-8`, `latest-1`);
//! - `caravan/G/record/H`: liveliness token, host H records the whole group (the clock host
//!   of a lockstep run): every host sends it every topic;
//! - `caravan/G/topic/H/TOPIC`: the messages of TOPIC for host H, with an [`Envelope`] as
//!   attachment.
//! - `caravan/G/type/TYPE`: a query, answered by each host whose processes registered message
//!   type TYPE with its descriptor.
//!
//! Group names, host names, topic names and type names (`caravan::Pose2D`) hold no character
//! zenoh reserves (`*`, `$`, `#`, `?`), so keys need no escaping.

use super::causal::Knowledge;
use caravan::Delivery;
use serde::{Deserialize, Serialize};

pub fn root(group: &str) -> String {
    format!("caravan/{group}")
}

/// The token of a launcher of `host`; `id` is `START-ZID` (see [`LauncherId`]), or `*`.
pub fn host(group: &str, host: &str, id: &str) -> String {
    format!("caravan/{group}/host/{host}/{id}")
}

/// The host and launcher of a `host/H/START-ZID` token.
pub fn host_of(key: &str) -> Option<(&str, LauncherId)> {
    let (rest, id) = key.rsplit_once('/')?;
    Some((last(rest), LauncherId::parse(id)?))
}

/// Who a launcher is: when it started, and its zenoh id. Of two launchers of one host, the
/// one that started later gives way (on a tie, the greater id).
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub struct LauncherId {
    pub start_ns: u64,
    pub zid: String,
}

impl LauncherId {
    pub fn key_chunk(&self) -> String {
        format!("{}-{}", self.start_ns, self.zid)
    }

    pub fn parse(chunk: &str) -> Option<Self> {
        let (start, zid) = chunk.split_once('-')?;
        Some(Self {
            start_ns: start.parse().ok()?,
            zid: zid.to_string(),
        })
    }
}

pub fn done(group: &str, host: &str) -> String {
    format!("caravan/{group}/done/{host}")
}

pub fn stop(group: &str) -> String {
    format!("caravan/{group}/stop")
}

pub fn record(group: &str, host: &str) -> String {
    format!("caravan/{group}/record/{host}")
}

/// The query for the descriptor of message type `type_name` (`caravan::Pose2D`).
pub fn message_type(group: &str, type_name: &str) -> String {
    format!("caravan/{group}/type/{type_name}")
}

/// The messages of `topic` sent to `host`: one stream per reading host, so each starts when
/// that host's reader is known, as a subscriber on one host gets what is sent after it came.
pub fn topic(group: &str, host: &str, topic: &str) -> String {
    format!("caravan/{group}/topic/{host}/{topic}")
}

/// The last chunk of a key: the host of a `done/H` or `record/H` token.
pub fn last(key: &str) -> &str {
    key.rsplit('/').next().unwrap_or(key)
}

/// A host's wish to receive a topic.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub struct Want {
    pub host: String,
    pub type_name: String,
    pub lossless: bool,
    pub depth: usize,
    pub topic: String,
}

impl Want {
    pub fn delivery(&self) -> Delivery {
        if self.lossless {
            Delivery::Lossless { depth: self.depth }
        } else {
            Delivery::Latest { depth: self.depth }
        }
    }

    pub fn key(&self, group: &str) -> String {
        format!(
            "caravan/{group}/want/{}/{}/{}/{}",
            self.host,
            self.type_name,
            contract(self.delivery()),
            self.topic
        )
    }

    /// Reads a key made by [`Want::key`].
    pub fn parse(group: &str, key: &str) -> Option<Want> {
        let rest = key.strip_prefix(&format!("caravan/{group}/want/"))?;
        let mut parts = rest.splitn(4, '/');
        let host = parts.next()?.to_string();
        let type_name = parts.next()?.to_string();
        let delivery = parse_contract(parts.next()?)?;
        let topic = parts.next()?.to_string();
        Some(Want {
            host,
            type_name,
            lossless: delivery.is_lossless(),
            depth: delivery.depth(),
            topic,
        })
    }
}

/// A delivery contract as keys and attachments write it: `lossless-8`, `latest-1`.
pub fn contract(delivery: Delivery) -> String {
    let kind = if delivery.is_lossless() {
        "lossless"
    } else {
        "latest"
    };
    format!("{kind}-{}", delivery.depth())
}

/// The deepest queue another host may have opened here: a queue is allocated at its depth, so
/// a depth from the network is capped (Caravan's deepest, the lossless default, is 256). Capped,
/// not refused: every message and wish still counts for the lockstep hand-off.
pub const MAX_NETWORK_DEPTH: usize = 4096;

fn parse_contract(text: &str) -> Option<Delivery> {
    let (kind, depth) = text.split_once('-')?;
    let depth = depth.parse::<usize>().ok()?.clamp(1, MAX_NETWORK_DEPTH);
    match kind {
        "lossless" => Some(Delivery::Lossless { depth }),
        "latest" => Some(Delivery::Latest { depth }),
        _ => None,
    }
}

/// What a host says when it stops the group.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StopNotice {
    pub host: String,
    /// "completed", "interrupted" or "failed".
    pub outcome: String,
    pub failure: Option<String>,
}

/// What travels with a message besides its payload, as its zenoh attachment: the header
/// (4 × u64, little-endian), then `TYPE HOST CONTRACT` and, on lockstep control messages,
/// ` KNOWLEDGE` (space-separated text).
#[derive(Debug, Clone, PartialEq)]
pub struct Envelope {
    pub header: caravan::Header,
    /// The message type's name, `caravan::Pose2D`.
    pub type_name: String,
    /// The sending host.
    pub host: String,
    /// The topic's delivery contract on the sending side.
    pub delivery: Delivery,
    /// What the sender knew had been sent, when the message must wait for it
    /// ([`super::causal`]).
    pub knowledge: Option<Knowledge>,
}

impl Envelope {
    pub fn to_bytes(&self) -> Vec<u8> {
        let h = &self.header;
        let mut out = Vec::with_capacity(64 + self.type_name.len() + self.host.len());
        for v in [h.seq, h.stamp_ns, h.send_wall_ns, h.source_id] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        let mut text = format!(
            "{} {} {}",
            self.type_name,
            self.host,
            contract(self.delivery)
        );
        if let Some(k) = &self.knowledge {
            text.push(' ');
            text.push_str(&k.encode());
        }
        out.extend_from_slice(text.as_bytes());
        out
    }

    /// Reads [`Self::to_bytes`]'s form; `None` for anything else.
    pub fn parse(bytes: &[u8]) -> Option<Envelope> {
        if bytes.len() < 32 {
            return None;
        }
        let word = |i: usize| u64::from_le_bytes(bytes[i * 8..i * 8 + 8].try_into().unwrap());
        let header = caravan::Header {
            seq: word(0),
            stamp_ns: word(1),
            send_wall_ns: word(2),
            source_id: word(3),
        };
        let text = std::str::from_utf8(&bytes[32..]).ok()?;
        let mut parts = text.splitn(4, ' ');
        let type_name = parts.next()?.to_string();
        let host = parts.next()?.to_string();
        let delivery = parse_contract(parts.next()?)?;
        let knowledge = match parts.next() {
            Some(k) => Some(Knowledge::parse(k)?),
            None => None,
        };
        Some(Envelope {
            header,
            type_name,
            host,
            delivery,
            knowledge,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_later_launcher_of_a_host_gives_way() {
        let first = LauncherId {
            start_ns: 5,
            zid: "ab12".into(),
        };
        let chunk = first.key_chunk();
        assert_eq!(chunk, "5-ab12");
        assert_eq!(LauncherId::parse(&chunk), Some(first.clone()));
        let later = LauncherId::parse("6-0f").unwrap();
        let tie = LauncherId::parse("5-ff").unwrap();
        assert!(later > first && tie > first);
        let key = host("g", "rpi-0", &later.key_chunk());
        assert_eq!(key, "caravan/g/host/rpi-0/6-0f");
        assert_eq!(host_of(&key), Some(("rpi-0", later)));
        assert_eq!(host_of("caravan/g/host/rpi-0"), None);
        for bad in ["", "5", "x-ab", "-ab"] {
            assert_eq!(LauncherId::parse(bad), None, "{bad}");
        }
    }

    #[test]
    fn want_keys_round_trip() {
        let want = Want {
            host: "rpi-0".into(),
            type_name: "caravan::Pose2D".into(),
            lossless: true,
            depth: 16,
            topic: "robot/0/pose".into(),
        };
        let key = want.key("g1");
        assert_eq!(
            key,
            "caravan/g1/want/rpi-0/caravan::Pose2D/lossless-16/robot/0/pose"
        );
        assert!(zenoh::key_expr::KeyExpr::new(key.clone()).is_ok());
        assert_eq!(Want::parse("g1", &key), Some(want));
        assert_eq!(Want::parse("g2", &key), None);
        assert_eq!(Want::parse("g1", "caravan/g1/want/a/T/sometimes-3/x"), None);
        // A depth from the network is capped: no queue of a billion messages, and none of 0.
        for (depth, capped) in [
            ("0", 1),
            ("4096", 4096),
            ("4097", 4096),
            ("1000000000", 4096),
        ] {
            let key = format!("caravan/g1/want/a/T/lossless-{depth}/x");
            assert_eq!(Want::parse("g1", &key).unwrap().depth, capped, "{depth}");
        }
    }

    #[test]
    fn envelopes_round_trip() {
        let mut envelope = Envelope {
            header: caravan::Header {
                seq: 7,
                stamp_ns: 1 << 40,
                send_wall_ns: 3,
                source_id: u64::MAX,
            },
            type_name: "caravan::Odometry".into(),
            host: "rpi-1".into(),
            delivery: Delivery::Latest { depth: 1 },
            knowledge: None,
        };
        let bytes = envelope.to_bytes();
        assert!(bytes.ends_with(b"caravan::Odometry rpi-1 latest-1"));
        assert_eq!(Envelope::parse(&bytes), Some(envelope.clone()));
        assert_eq!(Envelope::parse(&bytes[..31]), None);
        let mut k = Knowledge::default();
        k.sent.insert(("rpi-1".into(), "pc".into()), 4);
        k.wants.insert("pc".into(), 2);
        envelope.knowledge = Some(k);
        envelope.delivery = Delivery::Lossless { depth: 256 };
        assert_eq!(Envelope::parse(&envelope.to_bytes()), Some(envelope));
    }
}
