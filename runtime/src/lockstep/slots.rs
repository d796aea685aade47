//! Report slots: a node of the scheduler's machine writes its report of a quiet step into a
//! slot of the shared page (`pending.rs`) instead of publishing a `Done` sample, and the
//! scheduler then writes its grants there instead of publishing `Grant` samples.
//!
//! A `Done` sample is a loan and a send for the node and, for the scheduler, a receive that
//! looks at every node's publisher connected to the report service: a sixth of the
//! scheduler's thread in the convoy (docs/benchmarks.md, "Fourth round"). A slot is a plain
//! copy in shared memory, read by the scheduler only for the nodes it waits for. The
//! wake-up is unchanged: a report notifies when the count of quiet steps says it must.
//!
//! The scheduler gives each node holding the page a slot when it joins (the page's directory
//! maps slot to node hash); the node looks for it when it first reports a quiet step. A
//! step's slot is written by the node only after it was granted and read by the scheduler
//! only until it took the report, so the two never touch it at once: the `ready` word, written
//! last (release) and read first (acquire), orders the rest. Nodes without a slot (Python
//! nodes, another machine's, more nodes than slots) publish `Done` samples as before; the
//! scheduler reads both.
//!
//! Grants: once a node reported into its slot (so it knows the slot), the scheduler writes
//! its grants into the slot's first 64 bytes under a sequence number (a seqlock: odd while
//! being written), and wakes it as before. A grant may be written while the node reads the
//! last one (a repeat, or the stop), so the node reads until the sequence is even and the
//! same before and after.

use super::pending::{DIRECTORY, FIRST, Pending, REPORT, SIZE, SLOT, SLOTS};
use caravan_schemas::lockstep::{Grant, MAX_TOPICS};
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering, fence};

/// Looks at a grant being written before [`Pending::read_grant`] gives up: a write is two
/// stores apart, so only a writer stopped between them takes this many.
const TORN_READS: usize = 1 << 16;

/// A finished step, as a slot holds it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Report<'a> {
    pub now_ns: u64,
    /// Another step asked for at this time, 0 for none (`Done::wake_ns`).
    pub wake_ns: u64,
    /// `Done::undeclared`.
    pub undeclared: u32,
    /// `Done::flags`.
    pub flags: u32,
    /// Hashes of the topics the step published to (at most `MAX_TOPICS`).
    pub published: &'a [u64],
}

impl Pending {
    fn at(&self, offset: usize) -> *mut u8 {
        // A slot index from outside (these methods are public) must not reach past the map.
        assert!(
            offset < SIZE,
            "offset {offset} outside the page of quiet steps"
        );
        // SAFETY: in bounds of the map (SIZE bytes, checked when made or opened).
        unsafe { self.map.as_mut_ptr().add(offset) }
    }

    fn word(&self, offset: usize) -> &AtomicU64 {
        // SAFETY: an 8-aligned offset in the page (page-aligned), accessed only atomically
        // or, for the topics, under the `ready` word's ordering (module comment).
        unsafe { AtomicU64::from_ptr(self.at(offset).cast()) }
    }

    fn half(&self, offset: usize) -> &AtomicU32 {
        // SAFETY: as in `word`, 4-aligned.
        unsafe { AtomicU32::from_ptr(self.at(offset).cast()) }
    }

    fn entry(&self, slot: usize) -> &AtomicU64 {
        self.word(DIRECTORY + slot * 8)
    }

    fn report_at(&self, slot: usize) -> usize {
        FIRST + slot * SLOT + REPORT
    }

    /// The scheduler's side, when the node of `node_hash` joins: its slot, given it now (or
    /// kept from before its restart, its dead process's last report cleared: the new process
    /// may be granted that report's time again); `None` when every slot is taken (or for hash
    /// 0, the free mark).
    pub fn give_slot(&self, node_hash: u64) -> Option<usize> {
        if node_hash == 0 {
            return None;
        }
        let slot = match self.find_slot(node_hash) {
            Some(slot) => slot,
            None => (0..SLOTS).find(|&s| self.entry(s).load(Ordering::Acquire) == 0)?,
        };
        self.word(self.report_at(slot)).store(0, Ordering::Release);
        self.entry(slot).store(node_hash, Ordering::Release);
        Some(slot)
    }

    /// The node's side: the slot the scheduler gave it, if any.
    pub fn find_slot(&self, node_hash: u64) -> Option<usize> {
        (node_hash != 0)
            .then(|| (0..SLOTS).find(|&s| self.entry(s).load(Ordering::Acquire) == node_hash))
            .flatten()
    }

    /// The scheduler's side: writes `grant` into `slot` (the node learns of it when woken).
    pub fn write_grant(&self, slot: usize, grant: Grant) {
        let at = FIRST + slot * SLOT;
        let seq = self.word(at);
        let odd = seq.load(Ordering::Relaxed) | 1;
        seq.store(odd, Ordering::Relaxed);
        fence(Ordering::Release);
        self.word(at + 8).store(grant.now_ns, Ordering::Relaxed);
        self.word(at + 16).store(grant.tick_ns, Ordering::Relaxed);
        self.half(at + 24).store(grant.quiet, Ordering::Relaxed);
        self.half(at + 28).store(grant.stop, Ordering::Relaxed);
        self.word(at + 32).store(grant.until_ns, Ordering::Relaxed);
        seq.store(odd + 1, Ordering::Release);
    }

    /// The node's side: the grant in `slot` if it is newer than the one of sequence `seen`,
    /// with its sequence. `seen` is the sequence the slot holds when the node found it
    /// ([`Self::grant_sequence`]), then the last grant's.
    pub fn read_grant(&self, slot: usize, seen: u64) -> Option<(u64, Grant)> {
        let at = FIRST + slot * SLOT;
        let seq = self.word(at);
        // A writer that died between its two stores leaves the sequence odd: give up after a
        // while (the wait for a grant goes on, and ends at its time limit or the group's stop).
        for _ in 0..TORN_READS {
            let before = seq.load(Ordering::Acquire);
            if before == seen {
                return None;
            }
            if before & 1 == 1 {
                std::hint::spin_loop();
                continue;
            }
            let grant = Grant {
                now_ns: self.word(at + 8).load(Ordering::Relaxed),
                tick_ns: self.word(at + 16).load(Ordering::Relaxed),
                quiet: self.half(at + 24).load(Ordering::Relaxed),
                stop: self.half(at + 28).load(Ordering::Relaxed),
                until_ns: self.word(at + 32).load(Ordering::Relaxed),
            };
            fence(Ordering::Acquire);
            if seq.load(Ordering::Relaxed) == before {
                return Some((before, grant));
            }
        }
        None
    }

    /// The sequence of the last grant written into `slot` (see [`Self::read_grant`]).
    pub fn grant_sequence(&self, slot: usize) -> u64 {
        self.word(FIRST + slot * SLOT).load(Ordering::Acquire)
    }

    /// The node's side: writes the report of a step it was granted into its slot.
    pub fn write_report(&self, slot: usize, report: &Report) {
        let at = self.report_at(slot);
        let topics = &report.published[..report.published.len().min(MAX_TOPICS)];
        self.word(at + 8).store(report.wake_ns, Ordering::Relaxed);
        // The flags share a word: bit 0 undeclared, the report's flags above it.
        let flags = (report.undeclared != 0) as u32 | report.flags << 1;
        self.half(at + 16).store(flags, Ordering::Relaxed);
        self.half(at + 20)
            .store(topics.len() as u32, Ordering::Relaxed);
        // SAFETY: the topics' room is MAX_TOPICS words inside the slot; the scheduler reads
        // it only after `ready` says this step is in (module comment).
        unsafe {
            std::ptr::copy_nonoverlapping(topics.as_ptr(), self.at(at + 24).cast(), topics.len())
        };
        self.word(at)
            .store(report.now_ns.wrapping_add(1), Ordering::Release);
    }

    /// The scheduler's side: the report of the step at `now_ns` in `slot`, if it is in, its
    /// topics read into `topics`.
    pub fn read_report<'t>(
        &self,
        slot: usize,
        now_ns: u64,
        topics: &'t mut Vec<u64>,
    ) -> Option<Report<'t>> {
        let at = self.report_at(slot);
        if self.word(at).load(Ordering::Acquire) != now_ns.wrapping_add(1) {
            return None;
        }
        let len = (self.half(at + 20).load(Ordering::Relaxed) as usize).min(MAX_TOPICS);
        topics.clear();
        topics.resize(len, 0);
        // SAFETY: as in `write_report`: written before `ready`, which was read above.
        unsafe {
            std::ptr::copy_nonoverlapping(self.at(at + 24).cast::<u64>(), topics.as_mut_ptr(), len)
        };
        let topics: &'t Vec<u64> = topics;
        let flags = self.half(at + 16).load(Ordering::Relaxed);
        Some(Report {
            now_ns,
            wake_ns: self.word(at + 8).load(Ordering::Relaxed),
            undeclared: flags & 1,
            flags: flags >> 1,
            published: topics,
        })
    }

    /// The time of the last report written into `slot`, if any: a grant of several periods
    /// may end before its last ([`caravan_schemas::lockstep::Done::BURST`]).
    pub fn report_ns(&self, slot: usize) -> Option<u64> {
        let ready = self.word(self.report_at(slot)).load(Ordering::Acquire);
        (ready != 0).then(|| ready.wrapping_sub(1))
    }

    /// Whether the report of the step at `now_ns` is in `slot`.
    pub fn has_report(&self, slot: usize, now_ns: u64) -> bool {
        self.word(self.report_at(slot)).load(Ordering::Acquire) == now_ns.wrapping_add(1)
    }
}

#[cfg(test)]
mod tests {
    use super::super::pending::tests::config;
    use super::*;

    #[test]
    fn a_report_written_by_a_node_is_read_by_the_scheduler_for_its_step_only() {
        let config = config("slot-report");
        let scheduler = Pending::create(&config).unwrap();
        let node = Pending::open(&config).unwrap();
        let slot = scheduler.give_slot(42).unwrap();
        assert_eq!(node.find_slot(42), Some(slot));
        let mut topics = Vec::new();
        assert!(scheduler.read_report(slot, 10, &mut topics).is_none());
        let published = [7, 8, 9];
        let report = Report {
            now_ns: 10,
            wake_ns: 25,
            undeclared: 1,
            flags: 0,
            published: &published,
        };
        node.write_report(slot, &report);
        assert!(scheduler.has_report(slot, 10));
        // Another step's report is not this one.
        assert!(scheduler.read_report(slot, 20, &mut topics).is_none());
        let read = scheduler.read_report(slot, 10, &mut topics).unwrap();
        assert_eq!(read, report);
    }

    #[test]
    fn a_grant_is_read_once_and_the_newest_wins() {
        let config = config("slot-grant");
        let scheduler = Pending::create(&config).unwrap();
        let node = Pending::open(&config).unwrap();
        let slot = scheduler.give_slot(9).unwrap();
        let seen = node.grant_sequence(slot);
        assert!(node.read_grant(slot, seen).is_none());
        scheduler.write_grant(slot, Grant::step(10, 5).quiet(3));
        scheduler.write_grant(slot, Grant::step(20, 5).quiet(3));
        let (seen, grant) = node.read_grant(slot, seen).unwrap();
        assert_eq!(grant, Grant::step(20, 5).quiet(3));
        assert!(node.read_grant(slot, seen).is_none());
        scheduler.write_grant(slot, Grant::stop(20, 5));
        assert_eq!(node.read_grant(slot, seen).unwrap().1, Grant::stop(20, 5));
    }

    #[test]
    fn a_restarted_node_keeps_its_slot_cleared_and_slots_run_out() {
        let config = config("slot-give");
        let page = Pending::create(&config).unwrap();
        let first = page.give_slot(1).unwrap();
        let second = page.give_slot(2).unwrap();
        assert_ne!(first, second);
        // The dead process's last report is not the restarted one's, at the same time.
        let report = Report {
            now_ns: 30,
            wake_ns: 0,
            undeclared: 0,
            flags: 0,
            published: &[4],
        };
        page.write_report(first, &report);
        assert_eq!(page.give_slot(1), Some(first));
        assert!(!page.has_report(first, 30));
        assert_eq!(page.give_slot(0), None);
        for hash in 3..=SLOTS as u64 {
            assert!(page.give_slot(hash).is_some());
        }
        assert_eq!(page.give_slot(SLOTS as u64 + 1), None);
        assert_eq!(page.find_slot(SLOTS as u64 + 1), None);
    }

    #[test]
    fn the_most_topics_a_slot_holds_are_kept() {
        let config = config("slot-full");
        let page = Pending::create(&config).unwrap();
        let slot = page.give_slot(5).unwrap();
        let published: Vec<u64> = (1..=MAX_TOPICS as u64 + 3).collect();
        let report = Report {
            now_ns: 0,
            wake_ns: 0,
            undeclared: 0,
            flags: 0,
            published: &published,
        };
        page.write_report(slot, &report);
        let mut topics = Vec::new();
        let read = page.read_report(slot, 0, &mut topics).unwrap();
        assert_eq!(read.published, &published[..MAX_TOPICS]);
    }
}
