//! Which hosts of the group are up, which have finished, and what that means for this host:
//! the group starts once every required host joined, ends when every joined host finished,
//! and stops when a required host leaves before finishing.

use std::collections::{BTreeMap, BTreeSet};

/// What a change of presence tells the launcher.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Change {
    /// A host left before it finished; `required` hosts stop the group.
    Left { host: String, required: bool },
    /// Every host that joined has finished, and every required one joined.
    AllDone,
}

/// The hosts of the launch file and what is known of them.
#[derive(Debug, Clone)]
pub struct Presence {
    /// Every host of `[hosts]`, with its `required` flag.
    hosts: BTreeMap<String, bool>,
    up: BTreeSet<String>,
    done: BTreeSet<String>,
    /// Hosts whose leaving was already reported.
    left: BTreeSet<String>,
    /// The launchers up per host, by id: a host leaves when its last launcher does, so a
    /// second launcher of a host, which gives way, does not take the host with it.
    launchers: BTreeMap<String, BTreeSet<String>>,
    all_done_said: bool,
}

impl Presence {
    pub fn new(hosts: BTreeMap<String, bool>) -> Self {
        Self {
            hosts,
            up: BTreeSet::new(),
            done: BTreeSet::new(),
            left: BTreeSet::new(),
            launchers: BTreeMap::new(),
            all_done_said: false,
        }
    }

    /// Required hosts that are not up and have not finished: before the start, those to wait
    /// for; after it, those the group cannot end without.
    pub fn missing(&self) -> Vec<String> {
        self.hosts
            .iter()
            .filter(|(h, required)| **required && !self.up.contains(*h) && !self.done.contains(*h))
            .map(|(h, _)| h.clone())
            .collect()
    }

    /// Required hosts that left before they finished.
    pub fn lost(&self) -> Vec<String> {
        self.left
            .iter()
            .filter(|h| self.hosts.get(*h).copied().unwrap_or(false))
            .cloned()
            .collect()
    }

    /// Whether `host` is one of the launch file's.
    pub fn knows(&self, host: &str) -> bool {
        self.hosts.contains_key(host)
    }

    pub fn joined(&mut self, host: &str) -> Option<Change> {
        self.up.insert(host.to_string());
        self.left.remove(host);
        None
    }

    /// Launcher `id` of `host` is up.
    pub fn launcher_up(&mut self, host: &str, id: &str) -> Option<Change> {
        let ids = self.launchers.entry(host.to_string()).or_default();
        ids.insert(id.to_string());
        self.joined(host)
    }

    /// Launcher `id` of `host` went away; the host goes with its last launcher.
    pub fn launcher_down(&mut self, host: &str, id: &str) -> Vec<Change> {
        let ids = self.launchers.entry(host.to_string()).or_default();
        ids.remove(id);
        if ids.is_empty() {
            self.gone(host)
        } else {
            Vec::new()
        }
    }

    pub fn finished(&mut self, host: &str) -> Option<Change> {
        self.done.insert(host.to_string());
        self.all_done()
    }

    /// A host went away: a finished one changes nothing (it stays finished); one that had
    /// not finished has left, and the rest may now all be done.
    pub fn gone(&mut self, host: &str) -> Vec<Change> {
        if !self.up.remove(host) {
            return Vec::new();
        }
        if self.done.contains(host) {
            return self.all_done().into_iter().collect();
        }
        self.left.insert(host.to_string());
        let left = Change::Left {
            host: host.to_string(),
            required: self.hosts.get(host).copied().unwrap_or(false),
        };
        std::iter::once(left).chain(self.all_done()).collect()
    }

    fn all_done(&mut self) -> Option<Change> {
        let unfinished = self.up.iter().any(|h| !self.done.contains(h));
        if unfinished || !self.missing().is_empty() || self.all_done_said {
            return None;
        }
        self.all_done_said = true;
        Some(Change::AllDone)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fleet() -> Presence {
        Presence::new(BTreeMap::from([
            ("a".to_string(), true),
            ("b".to_string(), true),
            ("c".to_string(), false),
        ]))
    }

    #[test]
    fn the_group_waits_for_required_hosts_only() {
        let mut p = fleet();
        assert_eq!(p.missing(), ["a", "b"]);
        p.joined("a");
        p.joined("c");
        assert_eq!(p.missing(), ["b"]);
        p.joined("b");
        assert!(p.missing().is_empty());
    }

    #[test]
    fn a_host_leaves_with_its_last_launcher() {
        let mut p = fleet();
        p.launcher_up("b", "1-x");
        p.launcher_up("b", "2-y");
        assert!(p.launcher_down("b", "2-y").is_empty());
        assert!(p.lost().is_empty());
        let left = Change::Left {
            host: "b".into(),
            required: true,
        };
        assert_eq!(p.launcher_down("b", "1-x"), [left]);
        assert_eq!(p.lost(), ["b"]);
    }

    #[test]
    fn the_group_is_done_when_every_joined_host_is() {
        let mut p = fleet();
        for h in ["a", "b", "c"] {
            p.joined(h);
        }
        assert_eq!(p.finished("a"), None);
        assert_eq!(p.finished("b"), None);
        assert_eq!(p.finished("c"), Some(Change::AllDone));
        // Said once; hosts leaving after finishing change nothing.
        assert_eq!(p.gone("c"), []);
        assert_eq!(p.gone("a"), []);
    }

    #[test]
    fn leaving_early_is_reported_with_the_host_flag() {
        let mut p = fleet();
        for h in ["a", "b", "c"] {
            p.joined(h);
        }
        assert_eq!(
            p.gone("c"),
            [Change::Left {
                host: "c".into(),
                required: false
            }]
        );
        // The rest may still finish without c.
        p.finished("a");
        assert_eq!(p.finished("b"), Some(Change::AllDone));
        assert_eq!(fleet().gone("a"), [], "a host never seen cannot leave");
        let mut p = fleet();
        p.joined("a");
        assert_eq!(
            p.gone("a"),
            [Change::Left {
                host: "a".into(),
                required: true
            }]
        );
        assert_eq!(p.lost(), ["a"]);
        p.joined("a");
        assert!(p.lost().is_empty(), "a host that comes back is not lost");
    }

    #[test]
    fn a_host_that_finished_and_went_away_still_counts_as_finished() {
        let mut p = fleet();
        for h in ["a", "b", "c"] {
            p.joined(h);
        }
        p.finished("b");
        assert_eq!(p.gone("b"), []);
        assert!(p.missing().is_empty());
        p.finished("a");
        assert_eq!(p.finished("c"), Some(Change::AllDone));
    }

    #[test]
    fn an_optional_host_leaving_last_ends_the_group() {
        let mut p = fleet();
        for h in ["a", "b", "c"] {
            p.joined(h);
        }
        p.finished("a");
        p.finished("b");
        assert_eq!(
            p.gone("c"),
            [
                Change::Left {
                    host: "c".into(),
                    required: false
                },
                Change::AllDone
            ]
        );
    }
}
