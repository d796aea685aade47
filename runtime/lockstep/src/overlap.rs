//! When a node due one tick later may step while an earlier time is still running.
//!
//! A message published at t is visible from t + tick on, so a node due at T = t + tick reads
//! only messages from times ≤ t. It may start before every node of t has finished if none of
//! the unfinished ones can change what it reads or what they read, and if what it publishes
//! cannot land in a buffer beside a message of t (a one-deep "latest" buffer, the recorder's
//! tap, would lose the older one). So, against each node of t still stepping, the two share
//! no topic in either direction nor an output; against the nodes of t already done, its
//! outputs avoid what they published. Both must have declared their topics
//! ([`caravan_schemas::lockstep::Hello::declared`]); anything unknown never overlaps.

use std::collections::BTreeSet;

/// The topics a node touches, as the scheduler knows them.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Footprint {
    /// The node's inputs and outputs are all its topics, and it stamps with the granted time.
    pub declared: bool,
    /// Topic hashes it reads, sorted.
    pub inputs: Vec<u64>,
    /// Topic hashes it publishes to, sorted.
    pub outputs: Vec<u64>,
}

impl Footprint {
    pub fn new(declared: bool, inputs: &[u64], outputs: &[u64]) -> Self {
        let sorted = |list: &[u64]| {
            let mut v = list.to_vec();
            v.sort_unstable();
            v.dedup();
            v
        };
        Self {
            declared,
            inputs: sorted(inputs),
            outputs: sorted(outputs),
        }
    }
}

/// Whether two sorted lists have no element in common.
pub(crate) fn disjoint(a: &[u64], b: &[u64]) -> bool {
    // A physics process publishes hundreds of topics, a node reads a few: look each of the
    // few up rather than walk both.
    let (short, long) = if a.len() <= b.len() { (a, b) } else { (b, a) };
    if short.len() * 8 < long.len() {
        return short.iter().all(|t| long.binary_search(t).is_err());
    }
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => return false,
        }
    }
    true
}

/// Whether `node` may start while `running` (nodes of the earlier time still stepping)
/// finish. `published` is what the earlier time's finished nodes published; `known` the
/// topics that existed when the recorder last looked (a topic it has not seen yet gets its
/// tap after the earlier time ends, and must not be published to before that).
pub fn may_start<'a>(
    node: &Footprint,
    mut running: impl Iterator<Item = &'a Footprint>,
    published: &BTreeSet<u64>,
    known: &BTreeSet<u64>,
) -> bool {
    node.declared
        && node
            .outputs
            .iter()
            .all(|t| known.contains(t) && !published.contains(t))
        && running.all(|m| {
            m.declared
                && disjoint(&m.outputs, &node.inputs)
                && disjoint(&m.inputs, &node.outputs)
                && disjoint(&m.outputs, &node.outputs)
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fp(inputs: &[u64], outputs: &[u64]) -> Footprint {
        Footprint::new(true, inputs, outputs)
    }

    /// `may_start` with nothing published yet by the earlier time's finished nodes, and the
    /// recorder knowing topics 0 to 99.
    fn starts(node: &Footprint, running: &[&Footprint]) -> bool {
        may_start(
            node,
            running.iter().copied(),
            &BTreeSet::new(),
            &(0..100).collect(),
        )
    }

    #[test]
    fn nodes_sharing_no_topic_overlap() {
        // physics reads set-points (1), publishes poses (2); odometry reads encoders (3).
        let physics = fp(&[1], &[2]);
        let odometry = fp(&[3], &[4]);
        assert!(starts(&odometry, &[&physics]));
    }

    #[test]
    fn a_reader_of_a_running_node_waits() {
        let physics = fp(&[1], &[2]);
        let monitor = fp(&[2], &[5]);
        assert!(!starts(&monitor, &[&physics]));
    }

    #[test]
    fn a_writer_to_a_running_node_waits() {
        // The agent's new set-point would overwrite the one physics is about to read.
        let physics = fp(&[1], &[2]);
        let agent = fp(&[4], &[1]);
        assert!(!starts(&agent, &[&physics]));
    }

    #[test]
    fn two_writers_of_one_topic_do_not_overlap() {
        let a = fp(&[], &[7]);
        let b = fp(&[], &[7]);
        assert!(!starts(&b, &[&a]));
    }

    #[test]
    fn a_topic_published_by_a_finished_node_is_not_written_again_before_the_time_ends() {
        let b = fp(&[], &[7]);
        let published = BTreeSet::from([7]);
        assert!(!may_start(
            &b,
            std::iter::empty(),
            &published,
            &(0..100).collect()
        ));
        assert!(starts(&b, &[]));
    }

    #[test]
    fn undeclared_nodes_never_overlap() {
        let unknown = Footprint::new(false, &[], &[]);
        let plain = fp(&[3], &[4]);
        assert!(!starts(&unknown, &[]));
        assert!(!starts(&plain, &[&unknown]));
    }

    #[test]
    fn a_topic_the_recorder_has_not_seen_waits() {
        let b = fp(&[], &[700]);
        assert!(!starts(&b, &[]));
    }

    #[test]
    fn disjoint_walks_sorted_lists() {
        assert!(disjoint(&[1, 3, 5], &[2, 4, 6]));
        assert!(!disjoint(&[1, 3, 5], &[0, 5]));
        assert!(disjoint(&[], &[1]));
    }
}
