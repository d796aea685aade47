//! Per-node step statistics: steps, deadline misses, period jitter and compute time.
//!
//! Compute is measured twice: wall-clock time inside the step (what deadlines are about) and
//! the stepping thread's CPU time (what a host's CPU slowdown scales: on the emulating
//! machine a step also waits for a core, which a robot's own computer would not).

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
    cpu_sum_ns: u128,
    last_start_ns: Option<u64>,
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
            cpu_sum_ns: 0,
            last_start_ns: None,
        }
    }

    /// Records one step that started at `start_ns` (on a monotonic clock), was due at `due_ns`
    /// and took `compute` inside the step function.
    pub fn record(&mut self, start_ns: u64, due_ns: u64, compute: StepCompute) {
        let compute_ns = compute.wall_ns;
        self.steps += 1;
        self.compute.saturating_record(compute_ns.max(1));
        self.compute_sum_ns += compute_ns as u128;
        self.cpu_sum_ns += compute.cpu_ns as u128;
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
            compute_cpu_mean_ns: (self.cpu_sum_ns / u128::from(self.steps.max(1))) as u64,
            ..NodeStatus::default()
        }
    }
}

/// What one step took inside the step function, ns.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StepCompute {
    /// Wall-clock time, including any wait for a core.
    pub wall_ns: u64,
    /// CPU time of the stepping thread.
    pub cpu_ns: u64,
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
            cpu_ns: ms * 500_000,
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
