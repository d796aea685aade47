//! CPU time the processes of one measurement spend, so that a transport's latency is shown
//! next to what it costs (a spinning side buys its latency with CPU).

/// Nanoseconds process `pid` (every thread of it) has run on a CPU, from the kernel's
/// scheduler statistics (`/proc/PID/task/*/schedstat`, first field); `None` if it is gone. A
/// thread that is running now is counted up to its last scheduler tick only (≤ 4 ms behind).
pub fn cpu_ns(pid: u32) -> Option<u64> {
    let tasks = std::fs::read_dir(format!("/proc/{pid}/task")).ok()?;
    let mut total = 0;
    for task in tasks.flatten() {
        let text = std::fs::read_to_string(task.path().join("schedstat")).unwrap_or_default();
        total += text
            .split_whitespace()
            .next()
            .and_then(|ns| ns.parse::<u64>().ok())
            .unwrap_or(0);
    }
    Some(total)
}

/// The CPU time of this process and of others from a start to now.
pub struct CpuMeter {
    others: Vec<u32>,
    start_ns: Option<u64>,
}

impl CpuMeter {
    /// Measures this process and `others`.
    pub fn new(others: Vec<u32>) -> Self {
        Self {
            others,
            start_ns: None,
        }
    }

    fn total(&self) -> Option<u64> {
        let others: Option<u64> = self.others.iter().map(|&p| cpu_ns(p)).sum();
        Some(caravan::process_cpu_ns() + others?)
    }

    /// Starts counting from now.
    pub fn start(&mut self) {
        self.start_ns = self.total();
    }

    /// CPU ns of all the processes since [`Self::start`]; `None` if not started or one is gone.
    pub fn elapsed_ns(&self) -> Option<u64> {
        Some(self.total()?.saturating_sub(self.start_ns?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_busy_process_is_seen_spending_cpu() {
        let mut meter = CpuMeter::new(vec![]);
        assert_eq!(meter.elapsed_ns(), None);
        meter.start();
        let until = std::time::Instant::now() + std::time::Duration::from_millis(20);
        while std::time::Instant::now() < until {
            std::hint::spin_loop();
        }
        // How much depends on the machine's load; that it counted does not.
        let spent = meter.elapsed_ns().expect("this process exists");
        assert!(spent > 0, "{spent} ns");
    }

    #[test]
    fn a_process_that_does_not_exist_has_no_cpu_time() {
        assert_eq!(cpu_ns(u32::MAX), None);
    }
}
