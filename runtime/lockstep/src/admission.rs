//! Admission: the scheduler takes in the nodes that say hello, at the start and on restarts.

use crate::Watchdog;
use crate::members::Member;
use crate::overlap::Footprint;
use crate::scheduler::Scheduler;
use caravan::Error;
use caravan::lockstep::control::{notifier, publisher};
use caravan_schemas::lockstep::{self as proto, Grant, Hello};
use std::collections::BTreeSet;
use std::time::{Duration, Instant};

impl Scheduler {
    /// Waits until every node in `expected` said hello. `watchdog` runs between waits; an `Err`
    /// from it (a member died, a timeout) aborts the wait.
    pub fn wait_for_nodes(
        &mut self,
        expected: &[String],
        mut watchdog: impl Watchdog,
    ) -> Result<(), Error> {
        let mut expected: BTreeSet<&str> = expected.iter().map(String::as_str).collect();
        loop {
            self.admit_new()?;
            let joined: BTreeSet<&str> = self.members.iter().map(|m| &*m.name).collect();
            if expected.is_subset(&joined) {
                return Ok(());
            }
            let missing: Vec<&str> = expected.difference(&joined).copied().collect();
            let dead = watchdog(&missing).map_err(|why| {
                Error::Lockstep(format!(
                    "waiting for {} to start: {why}",
                    missing.join(", ")
                ))
            })?;
            // A process that died before joining is the supervisor's business (restart,
            // or stop the group if it was required); a restarted one joins later.
            for name in &dead {
                expected.remove(name.as_str());
            }
            self.wait_on(true)?;
        }
    }

    pub(crate) fn admit_new(&mut self) -> Result<(), Error> {
        while let Some(sample) = self
            .hello
            .receive()
            .map_err(|e| Error::transport("hello", e))?
        {
            self.admit(sample.payload())?;
        }
        Ok(())
    }

    fn footprint(&self, hello: &Hello) -> Footprint {
        // A period off the tick would put an event between two overlapping times.
        let declared = hello.declared != 0
            && hello.period_ns.is_multiple_of(self.tick_ns)
            && hello
                .triggers
                .as_slice()
                .iter()
                .all(|t| hello.inputs.as_slice().contains(t));
        Footprint::new(declared, hello.inputs.as_slice(), hello.outputs.as_slice())
    }

    /// Whether the node of `hello` holds this scheduler's count of quiet steps (a token is
    /// never 0: one of another machine or an earlier run differs).
    fn holds_count(&self, hello: &Hello) -> bool {
        (self.pending.as_ref()).is_some_and(|p| p.token() == hello.quiet)
    }

    /// The report slot of the node of `hello` (`caravan::lockstep::Pending::give_slot`): one
    /// holding the count reports into it.
    fn slot(&self, hello: &Hello, hash: u64) -> Option<usize> {
        let pending = self.pending.as_ref().filter(|_| self.holds_count(hello))?;
        pending.give_slot(hash)
    }

    fn admit(&mut self, hello: &Hello) -> Result<(), Error> {
        let name = hello.node.as_str().to_string();
        let hash = proto::name_hash(&name);
        if let Some(&i) = self.by_hash.get(&hash) {
            // A restarted process rejoins at the next tick.
            if !self.members[i].active {
                self.forget_rooms();
                let footprint = self.footprint(hello);
                let quiet = self.holds_count(hello);
                let slot = self.slot(hello, hash);
                let member = &mut self.members[i];
                member.active = true;
                member.quiet = quiet;
                member.container = hello.container;
                member.slot = slot;
                member.slot_grants = false;
                member.footprint = footprint;
                member.steps = 0;
                member.overlapped = false;
                member.output_depth = hello.output_depth;
                // After the steps its last batch took, which its readers have had.
                let batch = member.batch.clone();
                let after_batch = match batch.start() < batch.end() {
                    true => batch.end() + member.period_ns,
                    false => 0,
                };
                if member.steps_on_joining {
                    let at = (self.now_ns + self.tick_ns).max(after_batch);
                    self.insert(at, i)?;
                }
            }
            return Ok(());
        }
        let index = self.members.len();
        let grant_name = proto::grant_service(&name);
        self.members.push(Member {
            active: true,
            grant: publisher::<Grant>(&self.iox, &grant_name)?,
            grant_notifier: notifier(&self.iox, &grant_name)?,
            period_ns: hello.period_ns,
            steps_on_joining: hello.period_ns > 0 || hello.triggers.as_slice().is_empty(),
            footprint: self.footprint(hello),
            quiet: self.holds_count(hello),
            container: hello.container,
            slot: self.slot(hello, hash),
            slot_grants: false,
            steps: 0,
            overlapped: false,
            granted_at: Instant::now(),
            last_step: Duration::ZERO,
            triggered: !hello.triggers.as_slice().is_empty(),
            output_depth: hello.output_depth,
            bursty: false,
            batch: 0..=0,
            batch_published: Vec::new(),
            batch_times: Vec::new(),
            recent: std::collections::VecDeque::with_capacity(crate::members::RECENT),
            name: name.into(),
        });
        self.by_hash.insert(hash, index);
        for topic in hello.triggers.as_slice() {
            self.subscribers.entry(*topic).or_default().push(index);
        }
        self.forget_rooms();
        if self.members[index].steps_on_joining {
            // A node joining mid-run steps at the latest time being stepped.
            let at = self.flights.back().map_or(self.now_ns, |f| f.now_ns);
            self.insert(at, index)?;
        }
        Ok(())
    }
}
