//! Reports: how the scheduler learns that a node finished the step it was granted, from a
//! `Done` sample or the node's slot of the shared page, and what it schedules from it.

use crate::scheduler::Scheduler;
use caravan::Error;
use caravan::lockstep::Report;
use caravan::lockstep::control::has_samples;
use caravan_schemas::lockstep as proto;

impl Scheduler {
    pub(crate) fn receive_reports(&mut self) -> Result<(), Error> {
        while let Some(sample) = self
            .done
            .receive()
            .map_err(|e| Error::transport("done", e))?
        {
            // Read in place: a report is 4 KB, most of it the published topics' room.
            let done = sample.payload();
            let Some(&i) = self.by_hash.get(&done.node_hash) else {
                continue;
            };
            let report = Report {
                now_ns: done.now_ns,
                wake_ns: done.wake_ns,
                undeclared: done.undeclared,
                flags: done.flags,
                published: done.published.as_slice(),
            };
            self.take_report(i, &report)?;
        }
        self.read_slots()
    }

    /// The steps reported in the page's slots (`caravan::lockstep::Report`): looked for only
    /// in the slots of the nodes waited for.
    fn read_slots(&mut self) -> Result<(), Error> {
        let reported: Vec<(usize, usize, u64)> = self.slot_reports_in().collect();
        let mut topics = std::mem::take(&mut self.topics);
        let mut taken = Ok(());
        for (i, slot, now_ns) in reported {
            let pending = self.pending.as_ref().expect("a slot is in the page");
            let Some(report) = pending.read_report(slot, now_ns, &mut topics) else {
                continue;
            };
            if !self.members[i].slot_grants {
                self.members[i].slot_grants = true;
                self.forget_rooms();
            }
            self.stats.slot_reports += 1;
            taken = self.take_report(i, &report);
            if taken.is_err() {
                break;
            }
        }
        self.topics = topics;
        taken
    }

    /// The nodes waited for whose report is in their slot: (member, slot, time).
    fn slot_reports_in(&self) -> impl Iterator<Item = (usize, usize, u64)> + '_ {
        let pending = self.pending.as_ref();
        self.flights.iter().flat_map(move |f| {
            f.waiting.iter().filter_map(move |&i| {
                let slot = self.members[i].slot?;
                let batch = &self.members[i].batch;
                if *batch.start() == f.now_ns && batch.start() < batch.end() {
                    // A batch reports its last step, or the one it ended at.
                    let at = pending?.report_ns(slot)?;
                    return batch.contains(&at).then_some((i, slot, at));
                }
                (pending?.has_report(slot, f.now_ns)).then_some((i, slot, f.now_ns))
            })
        })
    }

    /// Whether a report is in (a `Done` sample, or a slot of a node waited for).
    pub(crate) fn reports_in(&self) -> Result<bool, Error> {
        Ok(has_samples(&self.done, proto::DONE)? || self.slot_reports_in().next().is_some())
    }

    /// Takes node `i`'s report of a step: schedules what it woke and what it asked for.
    fn take_report(&mut self, i: usize, report: &Report) -> Result<(), Error> {
        let newest = self.flights.back().map_or(self.now_ns, |f| f.now_ns);
        let granted_ns = self.granted_at(i, report.now_ns);
        if granted_ns > newest {
            return Err(Error::Lockstep(format!(
                "node '{}' reported a step at {} ns, but time is {} ns",
                self.members[i].name, report.now_ns, newest
            )));
        }
        // Repeats of reports (answers to repeated grants) are expected; skip them.
        let Some(f) = self.flights.iter_mut().find(|f| f.now_ns == granted_ns) else {
            return Ok(());
        };
        if !f.waiting.remove(&i) {
            return Ok(());
        }
        // A grant of several periods says which of its steps published where.
        let steps = crate::batch::steps_of(report);
        let published: std::borrow::Cow<[u64]> = match &steps {
            Some(steps) => steps.iter().map(|&(t, _)| t).collect(),
            None => report.published.into(),
        };
        match &steps {
            Some(steps) => f.published.extend(crate::batch::published_at(steps, 0)),
            None => f.published.extend(published.iter().copied()),
        }
        self.end_batch(i, report, steps.as_deref())?;
        // Its last step's time: what comes next is scheduled from there.
        let now_ns = report.now_ns;
        // A grant of several periods up to this time or later was decided on its declaration.
        let batching = (self.members.iter())
            .any(|m| m.batch.start() < m.batch.end() && *m.batch.end() >= granted_ns);
        // A first step and a topic opened after joining change what a batch's room reads.
        let late_topic = report.undeclared != 0 && self.members[i].footprint.declared;
        if self.members[i].steps == 0 || late_topic {
            self.forget_rooms();
        }
        let member = &mut self.members[i];
        member.last_step = member.granted_at.elapsed();
        member.steps += 1;
        member.stepped_at(granted_ns);
        for k in 0..member.batch_times.len() {
            member.stepped_at(member.batch_times[k]);
        }
        if late_topic {
            member.footprint.declared = false;
            if member.overlapped || batching {
                return Err(Error::Lockstep(format!(
                    "node '{}' opened a topic in its step at {now_ns} ns, after it joined \
                     the schedule, while nodes of another time stepped beside it or a node \
                     took several periods on one grant: a rerun could differ. Open a node's \
                     publishers and subscribers before its step loop",
                    member.name
                )));
            }
            tracing::warn!(
                "node '{}' opened a topic in its step at {now_ns} ns, after it joined the \
                 schedule: it is no longer stepped beside other ticks",
                member.name
            );
        }
        member.overlapped = false;
        match &steps {
            Some(steps) => self.schedule_batch_after(i, granted_ns, now_ns, steps)?,
            None => self.schedule_after(i, now_ns, &published)?,
        }
        if report.wake_ns > now_ns {
            self.insert(report.wake_ns, i)?;
        }
        Ok(())
    }
}
