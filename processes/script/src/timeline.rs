//! The timeline: which commands a step publishes, from the step's simulated time and what the
//! triggers saw. It knows no topics or messages, only when: each command is published
//!
//! - once, at the first step at or after its time ([`When::At`]);
//! - on every step from its start until (not including) its end, or, with a period, at the
//!   first step at or after each start + k · period before the end ([`When::Held`]);
//! - once, at the first step (from `after` on) whose trigger condition held
//!   ([`When::Trigger`]).
//!
//! Times are nanoseconds of simulated time, as `Step::now_ns` gives them. In lockstep a node's
//! steps fall at exact multiples of its period, so a command falls on the same step in every
//! run; a time between two steps is published at the later one.

/// When one command is published.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum When {
    /// Once, at the first step at or after this time.
    At(u64),
    /// From `from` until before `until` (`u64::MAX`: the end of the run): every step, or with
    /// `every`, at the first step at or after each `from + k · every`.
    Held {
        from: u64,
        until: u64,
        every: Option<u64>,
    },
    /// Once, at the first step at or after `after` at which trigger `trigger` held.
    Trigger { trigger: usize, after: u64 },
}

#[derive(Debug, Clone)]
struct Entry {
    when: When,
    /// A one-off command published, or a held one past its end.
    done: bool,
    /// A held command with a period: its next time.
    next: u64,
}

/// The commands' schedules, in the launch file's order.
#[derive(Debug, Clone)]
pub struct Timeline {
    entries: Vec<Entry>,
}

impl Timeline {
    pub fn new(whens: impl IntoIterator<Item = When>) -> Self {
        let entries = whens
            .into_iter()
            .map(|when| Entry {
                when,
                done: false,
                next: match when {
                    When::Held { from, .. } => from,
                    _ => 0,
                },
            })
            .collect();
        Timeline { entries }
    }

    /// The commands (indices, in order) to publish at the step at `now`; `held(t)` says whether
    /// trigger `t`'s condition held in what this step read. Call it once per step, with
    /// growing times.
    pub fn step(&mut self, now: u64, held: impl Fn(usize) -> bool) -> Vec<usize> {
        let mut due = Vec::new();
        for (i, e) in self.entries.iter_mut().enumerate() {
            if e.done {
                continue;
            }
            let publish = match e.when {
                When::At(at) => {
                    e.done = now >= at;
                    e.done
                }
                When::Trigger { trigger, after } => {
                    e.done = now >= after && held(trigger);
                    e.done
                }
                When::Held { until, .. } if now >= until => {
                    e.done = true;
                    false
                }
                When::Held { from, every, .. } => match every {
                    _ if now < from => false,
                    None => true,
                    Some(_) if now < e.next => false,
                    Some(every) => {
                        // The next time after this step: steps slower than the period skip
                        // the times between them rather than publish them late.
                        let k = (now - from) / every + 1;
                        e.next = from.saturating_add(k.saturating_mul(every));
                        true
                    }
                },
            };
            if publish {
                due.push(i);
            }
        }
        due
    }

    /// Whether no command is left to publish.
    pub fn finished(&self) -> bool {
        self.entries.iter().all(|e| e.done)
    }

    /// Whether a trigger's condition can still matter: some command waiting on it is not done.
    pub fn waits_on(&self, trigger: usize) -> bool {
        self.entries
            .iter()
            .any(|e| !e.done && matches!(e.when, When::Trigger { trigger: t, .. } if t == trigger))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;

    /// Steps `t` every `period` ms from 0 to `end` ms; returns (time in ms, commands) for each
    /// step that published, with `held` giving each trigger's condition at a time.
    fn run(
        whens: &[When],
        period: u64,
        end: u64,
        held: impl Fn(usize, u64) -> bool,
    ) -> Vec<(u64, Vec<usize>)> {
        let mut t = Timeline::new(whens.iter().copied());
        (0..=end / period)
            .map(|k| k * period * MS)
            .filter_map(|now| {
                let due = t.step(now, |trigger| held(trigger, now));
                (!due.is_empty()).then_some((now / MS, due))
            })
            .collect()
    }

    #[test]
    fn a_timed_command_falls_on_the_first_step_at_or_after_its_time() {
        let whens = [When::At(20 * MS), When::At(25 * MS), When::At(0)];
        let got = run(&whens, 10, 100, |_, _| false);
        assert_eq!(got, [(0, vec![2]), (20, vec![0]), (30, vec![1])]);
    }

    #[test]
    fn a_held_command_is_published_every_step_of_its_interval_and_not_at_its_end() {
        let whens = [When::Held {
            from: 30 * MS,
            until: 60 * MS,
            every: None,
        }];
        let got = run(&whens, 10, 100, |_, _| false);
        assert_eq!(got, [(30, vec![0]), (40, vec![0]), (50, vec![0])]);
        // Until the end of the run.
        let whens = [When::Held {
            from: 80 * MS,
            until: u64::MAX,
            every: None,
        }];
        let got = run(&whens, 10, 100, |_, _| false);
        assert_eq!(got, [(80, vec![0]), (90, vec![0]), (100, vec![0])]);
    }

    #[test]
    fn a_held_command_with_a_period_takes_the_first_step_at_or_after_each_time() {
        let held = |every| {
            [When::Held {
                from: 5 * MS,
                until: 100 * MS,
                every: Some(every * MS),
            }]
        };
        // Every 20 ms from 5 ms on 10 ms steps: 5 → 10, 25 → 30, 45 → 50, 65 → 70, 85 → 90.
        let times: Vec<u64> = run(&held(20), 10, 200, |_, _| false)
            .iter()
            .map(|s| s.0)
            .collect();
        assert_eq!(times, [10, 30, 50, 70, 90]);
        // A period shorter than the step: once per step, never twice.
        let times: Vec<u64> = run(&held(3), 10, 200, |_, _| false)
            .iter()
            .map(|s| s.0)
            .collect();
        assert_eq!(times, [10, 20, 30, 40, 50, 60, 70, 80, 90]);
    }

    #[test]
    fn a_trigger_fires_once_and_not_before_its_after_time() {
        let whens = [
            When::Trigger {
                trigger: 0,
                after: 0,
            },
            When::Trigger {
                trigger: 1,
                after: 50 * MS,
            },
        ];
        // Trigger 0 holds from 30 ms on; trigger 1 holds only at 20 ms and from 70 ms on.
        let held = |t, now| match t {
            0 => now >= 30 * MS,
            _ => now == 20 * MS || now >= 70 * MS,
        };
        let mut timeline = Timeline::new(whens);
        assert!(timeline.waits_on(0) && timeline.waits_on(1));
        let got = run(&whens, 10, 100, held);
        assert_eq!(got, [(30, vec![0]), (70, vec![1])]);
        for k in 0..=10 {
            timeline.step(k * 10 * MS, |t| held(t, k * 10 * MS));
        }
        assert!(timeline.finished());
        assert!(!timeline.waits_on(0));
    }

    #[test]
    fn commands_of_one_step_come_in_file_order_and_the_timeline_finishes() {
        let whens = [
            When::At(10 * MS),
            When::Held {
                from: 0,
                until: 20 * MS,
                every: None,
            },
            When::At(10 * MS),
        ];
        let mut t = Timeline::new(whens);
        assert_eq!(t.step(0, |_| false), [1]);
        assert_eq!(t.step(10 * MS, |_| false), [0, 1, 2]);
        assert!(!t.finished());
        assert!(t.step(20 * MS, |_| false).is_empty());
        assert!(t.finished());
    }
}
