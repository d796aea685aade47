//! Per-node step statistics: steps, deadline misses, period jitter and compute time.
//!
//! Compute is measured twice: wall-clock time inside the step (what deadlines are about) and
//! the stepping thread's CPU time (what a host's CPU slowdown scales: on the emulating
//! machine a step also waits for a core, which a robot's own computer would not).
//!
//! The wall clock is read at every step. The thread's CPU clock is a system call (no vDSO
//! serves it), two per step: for a node whose steps take microseconds that is a tenth of
//! its CPU. So it is read at every one of the first [`CPU_ALWAYS`] steps and then at one
//! step in [`CPU_ONE_IN`], picked at random ([`CpuSampling`]); the CPU mean weighs the first
//! steps and the later ones by their numbers of steps. A node with a CPU slowdown in lockstep
//! reads it at every step (its messages are stamped by it). Python nodes read it at every
//! step.

use caravan_schemas::NodeStatus;
use hdrhistogram::Histogram;
use std::time::Duration;

/// Accumulates what the run report shows about a node's execution.
pub struct StepStats {
    period_ns: u64,
    steps: u64,
    deadline_misses: u64,
    jitter: Histogram<u64>,
    compute: Histogram<u64>,
    compute_sum_ns: u128,
    /// CPU time of the first [`CPU_ALWAYS`] steps, then of the later ones: each part's steps
    /// are read at a rate of their own, so the mean weighs each part by its steps.
    cpu_early: CpuPart,
    cpu_later: CpuPart,
    cpu_sampling: CpuSampling,
    last_start_ns: Option<u64>,
}

/// The CPU time of a run of steps, some of them read.
#[derive(Debug, Clone, Copy, Default)]
struct CpuPart {
    steps: u64,
    read: u64,
    sum_ns: u128,
}

impl CpuPart {
    fn record(&mut self, cpu_ns: Option<u64>) {
        self.steps += 1;
        if let Some(ns) = cpu_ns {
            self.read += 1;
            self.sum_ns += ns as u128;
        }
    }
}

/// Steps whose CPU clock is read before sampling starts: a short run's mean stays exact.
pub(crate) const CPU_ALWAYS: u64 = 64;
/// After [`CPU_ALWAYS`] steps, one step in this many has its CPU clock read.
pub(crate) const CPU_ONE_IN: u64 = 8;

/// Picks one step in [`CPU_ONE_IN`] at random, so that a node whose work repeats every few
/// steps is not read at the same phase each time. Seeded alike in every node: which steps
/// are read is the same on a rerun.
#[derive(Debug, Clone)]
pub(crate) struct CpuSampling {
    /// xorshift64 state, never 0.
    state: u64,
}

impl Default for CpuSampling {
    fn default() -> Self {
        Self {
            state: 0x9E37_79B9_7F4A_7C15,
        }
    }
}

impl CpuSampling {
    /// Whether the next step is picked.
    pub(crate) fn next_picked(&mut self) -> bool {
        let mut x = self.state;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.state = x;
        x.is_multiple_of(CPU_ONE_IN)
    }
}

impl StepStats {
    /// `period` is `None` for a node stepped by messages: it has no jitter or deadline.
    pub fn new(period: Option<Duration>) -> Self {
        let histogram =
            || Histogram::new_with_bounds(1, 3_600_000_000_000, 3).expect("valid bounds");
        Self {
            period_ns: period.map_or(0, |p| p.as_nanos() as u64),
            steps: 0,
            deadline_misses: 0,
            jitter: histogram(),
            compute: histogram(),
            compute_sum_ns: 0,
            cpu_early: CpuPart::default(),
            cpu_later: CpuPart::default(),
            cpu_sampling: CpuSampling::default(),
            last_start_ns: None,
        }
    }

    /// Whether the next step's CPU clock is to be read (the first 64 steps, then one in 8 at
    /// random); ask once per step.
    pub fn cpu_due(&mut self) -> bool {
        // Drawn at every step, so that which later steps are read does not depend on how
        // the early ones went.
        let picked = self.cpu_sampling.next_picked();
        self.steps < CPU_ALWAYS || picked
    }

    /// Records one step that started at `start_ns` (on a monotonic clock), was due at `due_ns`
    /// and took `compute` inside the step function.
    pub fn record(&mut self, start_ns: u64, due_ns: u64, compute: StepCompute) {
        let compute_ns = compute.wall_ns;
        self.steps += 1;
        self.compute.saturating_record(compute_ns.max(1));
        self.compute_sum_ns += compute_ns as u128;
        if self.steps <= CPU_ALWAYS {
            self.cpu_early.record(compute.cpu_ns);
        } else {
            self.cpu_later.record(compute.cpu_ns);
        }
        if self.period_ns > 0 {
            if let Some(last) = self.last_start_ns {
                let actual = start_ns.saturating_sub(last);
                self.jitter
                    .saturating_record(actual.abs_diff(self.period_ns).max(1));
            }
            let late = start_ns.saturating_sub(due_ns);
            if late > self.period_ns || compute_ns > self.period_ns {
                self.deadline_misses += 1;
            }
        }
        self.last_start_ns = Some(start_ns);
    }

    /// The mean CPU time per step: each part's steps read stand for all its steps (a part
    /// none of whose steps was read is left out).
    fn cpu_mean_ns(&self) -> u64 {
        let (mut total, mut steps) = (0u128, 0u128);
        for part in [self.cpu_early, self.cpu_later] {
            if part.read > 0 {
                total += part.sum_ns * u128::from(part.steps) / u128::from(part.read);
                steps += u128::from(part.steps);
            }
        }
        (total / steps.max(1)) as u64
    }

    /// The statistics as a `NodeStatus` (identity, missed messages and time left for the
    /// caller to fill in).
    pub fn summary(&self) -> NodeStatus {
        let pick =
            |h: &Histogram<u64>, f: fn(&Histogram<u64>) -> u64| if h.is_empty() { 0 } else { f(h) };
        NodeStatus {
            period_ns: self.period_ns,
            steps: self.steps,
            deadline_misses: self.deadline_misses,
            jitter_p50_ns: pick(&self.jitter, |h| h.value_at_quantile(0.5)),
            jitter_p99_ns: pick(&self.jitter, |h| h.value_at_quantile(0.99)),
            jitter_max_ns: pick(&self.jitter, |h| h.max()),
            compute_mean_ns: (self.compute_sum_ns / u128::from(self.steps.max(1))) as u64,
            compute_p99_ns: pick(&self.compute, |h| h.value_at_quantile(0.99)),
            compute_max_ns: pick(&self.compute, |h| h.max()),
            compute_cpu_mean_ns: self.cpu_mean_ns(),
            ..NodeStatus::default()
        }
    }
}

/// What one step took inside the step function, ns.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StepCompute {
    /// Wall-clock time, including any wait for a core.
    pub wall_ns: u64,
    /// CPU time of the stepping thread; `None` for a step whose CPU clock was not read
    /// ([`StepStats::cpu_due`]).
    pub cpu_ns: Option<u64>,
}

/// The calling thread's CPU time, ns (0 where the clock cannot be read).
pub fn thread_cpu_ns() -> u64 {
    cpu_clock_ns(libc::CLOCK_THREAD_CPUTIME_ID)
}

/// This process's CPU time, every thread of it, ns (0 where the clock cannot be read).
pub fn process_cpu_ns() -> u64 {
    cpu_clock_ns(libc::CLOCK_PROCESS_CPUTIME_ID)
}

fn cpu_clock_ns(clock: libc::clockid_t) -> u64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes only into `t`, which outlives the call.
    if unsafe { libc::clock_gettime(clock, &mut t) } != 0 {
        return 0;
    }
    t.tv_sec as u64 * 1_000_000_000 + t.tv_nsec as u64
}

/// The resident memory of this process, KiB, from /proc/self/statm (0 where it cannot be read).
pub fn resident_kib() -> u64 {
    let pages = std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| s.split_whitespace().nth(1)?.parse::<u64>().ok())
        .unwrap_or(0);
    // SAFETY: sysconf only reads a system constant.
    let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) }.max(0) as u64;
    pages * page / 1024
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn late_and_long_steps_are_deadline_misses() {
        let mut s = StepStats::new(Some(Duration::from_millis(10)));
        let took = |ms: u64| StepCompute {
            wall_ns: ms * 1_000_000,
            cpu_ns: Some(ms * 500_000),
        };
        s.record(0, 0, took(1)); // on time
        s.record(10_500_000, 10_000_000, took(1)); // 0.5 ms late: jitter, no miss
        s.record(35_000_000, 20_000_000, took(1)); // 15 ms late: miss
        s.record(40_000_000, 40_000_000, took(12)); // too long: miss
        let sum = s.summary();
        assert_eq!(sum.steps, 4);
        assert_eq!(sum.deadline_misses, 2);
        assert!(sum.jitter_max_ns >= 14_000_000);
        assert_eq!(sum.compute_mean_ns, 3_750_000);
        assert_eq!(sum.compute_cpu_mean_ns, 1_875_000);
    }

    #[test]
    fn the_cpu_mean_weighs_the_early_steps_and_the_sampled_ones_by_their_steps() {
        let mut s = StepStats::new(None);
        let step = |cpu_ns| StepCompute {
            wall_ns: 1_000,
            cpu_ns,
        };
        // 64 early steps of 3 µs, all read; 64 later ones of 1 µs, one in 8 read.
        for _ in 0..CPU_ALWAYS {
            s.record(0, 0, step(Some(3_000)));
        }
        for k in 0..64 {
            s.record(0, 0, step((k % 8 == 0).then_some(1_000)));
        }
        let sum = s.summary();
        assert_eq!(sum.steps, 128);
        // The true mean; a mean over the steps read would say (64 × 3 + 8 × 1) / 72 µs.
        assert_eq!(sum.compute_cpu_mean_ns, 2_000);
        assert_eq!(StepStats::new(None).summary().compute_cpu_mean_ns, 0);
        // Later steps none of which was read: the early ones stand for the run.
        let mut s = StepStats::new(None);
        for k in 0..70u64 {
            s.record(0, 0, step((k < CPU_ALWAYS).then_some(3_000)));
        }
        assert_eq!(s.summary().compute_cpu_mean_ns, 3_000);
    }

    #[test]
    fn every_early_step_is_read_then_one_in_eight_at_no_fixed_phase() {
        let mut stats = StepStats::new(None);
        let due: Vec<bool> = (0..80_064)
            .map(|_| {
                let due = stats.cpu_due();
                stats.record(0, 0, StepCompute::default());
                due
            })
            .collect();
        assert!(due[..CPU_ALWAYS as usize].iter().all(|&d| d));
        let later = &due[CPU_ALWAYS as usize..];
        let read = later.iter().filter(|&&d| d).count();
        // 10,000 expected; a binomial's standard deviation here is under 100.
        assert!(
            (9_500..=10_500).contains(&read),
            "{read} of {}",
            later.len()
        );
        // Each phase of a node whose work repeats every 10 steps is read about as often.
        for phase in 0..10 {
            let at_phase = later.iter().skip(phase).step_by(10).filter(|&&d| d).count();
            assert!(
                (850..=1_150).contains(&at_phase),
                "phase {phase}: {at_phase}"
            );
        }
        // A rerun reads the same steps.
        let mut again = StepStats::new(None);
        assert!(due.iter().all(|&d| {
            let same = again.cpu_due() == d;
            again.record(0, 0, StepCompute::default());
            same
        }));
    }

    #[test]
    fn thread_cpu_time_counts_work_and_not_sleep() {
        let before = thread_cpu_ns();
        std::thread::sleep(Duration::from_millis(50));
        let slept = thread_cpu_ns() - before;
        let before = thread_cpu_ns();
        let mut x = 0u64;
        while thread_cpu_ns() - before < 5_000_000 {
            x = std::hint::black_box(x.wrapping_add(1));
        }
        assert!(slept < 5_000_000, "sleeping cost {slept} ns of CPU");
        assert!(x > 0);
    }
}
