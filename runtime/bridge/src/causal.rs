//! What a lockstep control message needs before it may be delivered on another host.
//!
//! A step's messages and its report travel different paths: the data goes straight to each
//! reading host, the report ([`Done`]) to the clock host, whose grants then go to the next
//! nodes' hosts. A grant must not reach a node before the data it is meant to see, or a run
//! across hosts would differ from one on one host. So every host counts what it sent to each
//! other host, and the wishes to read topics (`want` tokens) it declared; every control
//! message carries what its sending host knows of those counts ([`Knowledge`], like a vector
//! clock), and the receiving bridge holds it until it has received as many messages from each
//! host, and handled as many of each host's wishes, as the sender knew had been sent.
//!
//! Counts only grow, so knowledge merges by taking the larger of two counts.
//!
//! [`Done`]: caravan::schemas::lockstep::Done

use std::collections::BTreeMap;

/// Counts of what hosts have sent, as far as one host knows.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Knowledge {
    /// (from, to) → data messages `from` sent to `to`.
    pub sent: BTreeMap<(String, String), u64>,
    /// host → wishes to read (want and record tokens) it declared.
    pub wants: BTreeMap<String, u64>,
}

/// What a host has received so far.
#[derive(Debug, Clone, Default)]
pub struct Received {
    /// host → data messages received from it (published here, or refused).
    pub messages: BTreeMap<String, u64>,
    /// host → its wishes to read that this host's outbound side has acted on.
    pub wants: BTreeMap<String, u64>,
}

impl Knowledge {
    /// Takes the larger of each count.
    pub fn merge(&mut self, other: &Knowledge) {
        fn max_into<K: Ord + Clone>(into: &mut BTreeMap<K, u64>, from: &BTreeMap<K, u64>) {
            for (k, &n) in from {
                let e = into.entry(k.clone()).or_default();
                *e = (*e).max(n);
            }
        }
        max_into(&mut self.sent, &other.sent);
        max_into(&mut self.wants, &other.wants);
    }

    /// Whether `me` has what this knowledge says was sent to it: each other host's messages to
    /// `me` and its wishes to read.
    pub fn is_met(&self, me: &str, got: &Received) -> bool {
        let count = |m: &BTreeMap<String, u64>, h: &str| m.get(h).copied().unwrap_or(0);
        self.sent
            .iter()
            .filter(|((from, to), _)| to == me && from != me)
            .all(|((from, _), &n)| count(&got.messages, from) >= n)
            && self
                .wants
                .iter()
                .filter(|(host, _)| *host != me)
                .all(|(host, &n)| count(&got.wants, host) >= n)
    }

    /// The text form carried in an attachment: `from>to=n` and `host=n`, comma-separated.
    /// Host names hold no `>`, `=`, `,` or space (the launch file allows letters, digits,
    /// `-`, `_` and `.`).
    pub fn encode(&self) -> String {
        let sent = self.sent.iter().map(|((f, t), n)| format!("{f}>{t}={n}"));
        let wants = self.wants.iter().map(|(h, n)| format!("{h}={n}"));
        sent.chain(wants).collect::<Vec<_>>().join(",")
    }

    /// Reads [`Self::encode`]'s form.
    pub fn parse(text: &str) -> Option<Knowledge> {
        let mut k = Knowledge::default();
        for item in text.split(',').filter(|s| !s.is_empty()) {
            let (key, n) = item.split_once('=')?;
            let n: u64 = n.parse().ok()?;
            match key.split_once('>') {
                Some((from, to)) => k.sent.insert((from.into(), to.into()), n),
                None => k.wants.insert(key.into(), n),
            };
        }
        Some(k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn knowledge(sent: &[(&str, &str, u64)], wants: &[(&str, u64)]) -> Knowledge {
        Knowledge {
            sent: sent
                .iter()
                .map(|(f, t, n)| ((f.to_string(), t.to_string()), *n))
                .collect(),
            wants: wants.iter().map(|(h, n)| (h.to_string(), *n)).collect(),
        }
    }

    #[test]
    fn encodes_and_parses() {
        let k = knowledge(&[("rpi-0", "pc", 12), ("pc", "rpi-1", 3)], &[("pc", 2)]);
        assert_eq!(k.encode(), "pc>rpi-1=3,rpi-0>pc=12,pc=2");
        assert_eq!(Knowledge::parse(&k.encode()), Some(k));
        assert_eq!(Knowledge::parse(""), Some(Knowledge::default()));
        assert_eq!(Knowledge::parse("a>b=x"), None);
        assert_eq!(Knowledge::parse("a>b"), None);
    }

    #[test]
    fn merging_keeps_the_larger_count() {
        let mut a = knowledge(&[("x", "y", 5), ("y", "x", 1)], &[("x", 1)]);
        a.merge(&knowledge(
            &[("x", "y", 3), ("z", "x", 2)],
            &[("x", 4), ("z", 1)],
        ));
        assert_eq!(
            a,
            knowledge(
                &[("x", "y", 5), ("y", "x", 1), ("z", "x", 2)],
                &[("x", 4), ("z", 1)]
            )
        );
    }

    #[test]
    fn a_message_waits_for_what_was_sent_to_its_host() {
        let k = knowledge(
            &[
                ("a", "me", 2),
                ("b", "me", 1),
                ("a", "b", 9),
                ("me", "a", 7),
            ],
            &[("a", 1), ("me", 5)],
        );
        let mut got = Received::default();
        assert!(!k.is_met("me", &got));
        got.messages.insert("a".into(), 2);
        got.messages.insert("b".into(), 1);
        // Data is in, but a's wish to read is not handled yet.
        assert!(!k.is_met("me", &got));
        got.wants.insert("a".into(), 1);
        // Counts between other hosts, and this host's own, are not its business.
        assert!(k.is_met("me", &got));
        got.messages.insert("b".into(), 0);
        assert!(!k.is_met("me", &got));
    }
}
