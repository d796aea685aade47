//! The zenoh key space of a group: everything a group says between hosts lives under
//! `caravan/GROUP/`, so two groups on one network never hear each other.
//!
//! - `caravan/G/host/H`: liveliness token, host H's launcher is up;
//! - `caravan/G/done/H`: liveliness token, every process of host H has exited;
//! - `caravan/G/stop`: a put, a host stopped the group (JSON [`StopNotice`]);
//! - `caravan/G/want/H/TYPE/CONTRACT/TOPIC`: liveliness token, a process of host H reads
//!   TOPIC, of message type TYPE with delivery CONTRACT (`lossless-8`, `latest-1`);
//! - `caravan/G/topic/H/TOPIC`: the messages of TOPIC for host H, header, type and sending
//!   host in the attachment.
//!
//! Group names, host names, topic names and type names (`caravan::Pose2D`) hold no character
//! zenoh reserves (`*`, `$`, `#`, `?`), so keys need no escaping.

use caravan::Delivery;
use serde::{Deserialize, Serialize};

pub fn root(group: &str) -> String {
    format!("caravan/{group}")
}

pub fn host(group: &str, host: &str) -> String {
    format!("caravan/{group}/host/{host}")
}

pub fn done(group: &str, host: &str) -> String {
    format!("caravan/{group}/done/{host}")
}

pub fn stop(group: &str) -> String {
    format!("caravan/{group}/stop")
}

/// The messages of `topic` sent to `host`: one stream per reading host, so each starts when
/// that host's reader is known, as a subscriber on one host gets what is sent after it came.
pub fn topic(group: &str, host: &str, topic: &str) -> String {
    format!("caravan/{group}/topic/{host}/{topic}")
}

/// The last chunk of a key: the host of a `host/H` or `done/H` token.
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
        let contract = if self.lossless { "lossless" } else { "latest" };
        format!(
            "caravan/{group}/want/{}/{}/{contract}-{}/{}",
            self.host, self.type_name, self.depth, self.topic
        )
    }

    /// Reads a key made by [`Want::key`].
    pub fn parse(group: &str, key: &str) -> Option<Want> {
        let rest = key.strip_prefix(&format!("caravan/{group}/want/"))?;
        let mut parts = rest.splitn(4, '/');
        let host = parts.next()?.to_string();
        let type_name = parts.next()?.to_string();
        let (contract, depth) = parts.next()?.split_once('-')?;
        let topic = parts.next()?.to_string();
        Some(Want {
            host,
            type_name,
            lossless: match contract {
                "lossless" => true,
                "latest" => false,
                _ => return None,
            },
            depth: depth.parse().ok()?,
            topic,
        })
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

/// The attachment of a message: its header (4 × u64, little-endian), its type's name and
/// the sending host, separated by a space.
pub fn attachment(header: &caravan::Header, type_name: &str, host: &str) -> Vec<u8> {
    let mut out = Vec::with_capacity(33 + type_name.len() + host.len());
    for v in [
        header.seq,
        header.stamp_ns,
        header.send_wall_ns,
        header.source_id,
    ] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(type_name.as_bytes());
    out.push(b' ');
    out.extend_from_slice(host.as_bytes());
    out
}

/// Reads an [`attachment`].
pub fn parse_attachment(bytes: &[u8]) -> Option<(caravan::Header, &str, &str)> {
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
    let (type_name, host) = std::str::from_utf8(&bytes[32..]).ok()?.split_once(' ')?;
    Some((header, type_name, host))
}

#[cfg(test)]
mod tests {
    use super::*;

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
    }

    #[test]
    fn attachments_round_trip() {
        let header = caravan::Header {
            seq: 7,
            stamp_ns: 1 << 40,
            send_wall_ns: 3,
            source_id: u64::MAX,
        };
        let bytes = attachment(&header, "caravan::Odometry", "rpi-1");
        assert_eq!(
            parse_attachment(&bytes),
            Some((header, "caravan::Odometry", "rpi-1"))
        );
        assert_eq!(parse_attachment(&bytes[..31]), None);
    }
}
