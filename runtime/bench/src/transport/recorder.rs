//! What one measurement collects: the one-way latency of each measured round trip, and how many
//! bytes moved per second while they ran.

use super::cpu::CpuMeter;
use anyhow::{Result, bail};
use hdrhistogram::Histogram;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Counts round trips, records the measured ones (after warm-up) as one-way latencies.
pub struct Recorder {
    hist: Histogram<u64>,
    bytes: usize,
    warmup: u64,
    total: u64,
    done: u64,
    /// When the warm-up ended, and when the last round trip did.
    measured: Option<(Instant, Instant)>,
    progress: ProgressBar,
    alive: Arc<AtomicU64>,
    /// The CPU time of both sides over the measured round trips.
    cpu: CpuMeter,
    /// CPU ns both sides spent, read at the last round trip: before the stop message, so the
    /// echoing side's shutdown is not counted (and its threads are still there to be read).
    cpu_spent_ns: Option<u64>,
}

/// A finished measurement.
pub struct Measured {
    pub hist: Histogram<u64>,
    /// Payload bytes moved per second over the measured round trips, both ways (each echo is
    /// a message too): with one message in flight, the payload over the one-way latency.
    pub bytes_per_s: f64,
    /// CPU time both sides spent per message (a round trip is two), ns; `None` if unknown.
    pub cpu_ns_per_message: Option<f64>,
}

impl Recorder {
    /// `total` round trips of `bytes`, the first `warmup` of them not measured; `alive` counts
    /// them for the watchdog; `cpu` measures the processes of both sides.
    pub fn new(
        bytes: usize,
        total: u64,
        warmup: u64,
        progress: ProgressBar,
        alive: Arc<AtomicU64>,
        cpu: CpuMeter,
    ) -> Self {
        Self {
            hist: caravan_report::bench::histogram(),
            bytes,
            warmup,
            total,
            done: 0,
            measured: None,
            progress,
            alive,
            cpu,
            cpu_spent_ns: None,
        }
    }

    /// Round trips to make, warm-up included.
    pub fn total(&self) -> u64 {
        self.total
    }

    /// Records one round trip's time.
    pub fn record(&mut self, rtt: Duration) {
        let now = Instant::now();
        if self.done >= self.warmup {
            self.hist
                .saturating_record((rtt.as_nanos() as u64 / 2).max(1));
        }
        self.done += 1;
        if self.done == self.total {
            self.cpu_spent_ns = self.cpu.elapsed_ns();
        }
        if self.done == self.warmup {
            self.measured = Some((now, now));
            self.cpu.start();
        } else if let Some((_, last)) = &mut self.measured {
            *last = now;
        }
        self.alive.store(self.done, Ordering::Relaxed);
        if self.done.is_multiple_of(64) {
            self.progress.inc(64);
        }
    }

    pub fn finish(self) -> Result<Measured> {
        self.progress.inc(self.done % 64);
        if self.done < self.total {
            bail!("stopped after {} of {} round trips", self.done, self.total);
        }
        let seconds = self
            .measured
            .map_or(0.0, |(from, to)| (to - from).as_secs_f64());
        let messages = 2.0 * (self.total - self.warmup) as f64;
        let moved = messages * self.bytes as f64;
        Ok(Measured {
            hist: self.hist,
            bytes_per_s: if seconds > 0.0 { moved / seconds } else { 0.0 },
            cpu_ns_per_message: self
                .cpu_spent_ns
                .filter(|_| messages > 0.0)
                .map(|ns| ns as f64 / messages),
        })
    }
}

/// The bar of the whole run: every measurement's round trips.
pub fn progress_bar(pairs: usize, rounds_per_pair: u64) -> ProgressBar {
    // Drawn on stderr only when it is a terminal; never in tests or pipes.
    let bar = ProgressBar::with_draw_target(
        Some(pairs as u64 * rounds_per_pair),
        ProgressDrawTarget::stderr(),
    );
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {percent:>3}% {elapsed_precise} eta {eta} {msg}")
            .expect("valid progress template"),
    );
    bar
}

#[cfg(test)]
mod tests {
    use super::*;

    fn recorder(bytes: usize, total: u64, warmup: u64) -> Recorder {
        let (bar, alive) = (ProgressBar::hidden(), Arc::default());
        Recorder::new(bytes, total, warmup, bar, alive, CpuMeter::new(vec![]))
    }

    #[test]
    fn only_rounds_after_the_warm_up_are_measured() {
        let mut rec = recorder(1000, 5, 2);
        for _ in 0..5 {
            rec.record(Duration::from_micros(100));
            std::thread::sleep(Duration::from_millis(1));
        }
        let m = rec.finish().unwrap();
        assert_eq!(m.hist.len(), 3);
        // 3 round trips of 1000 B each way over at least 3 ms.
        assert!(
            m.bytes_per_s > 0.0 && m.bytes_per_s <= 6000.0 / 0.003,
            "{}",
            m.bytes_per_s
        );
    }

    #[test]
    fn a_measurement_cut_short_is_an_error() {
        let mut rec = recorder(16, 5, 1);
        rec.record(Duration::from_micros(1));
        assert!(rec.finish().is_err());
    }
}
