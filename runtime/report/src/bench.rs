//! Shared pieces of Caravan's benchmarks: the machine they ran on, latency percentiles, the
//! CPU time of a child process, and writing a result table.

use anyhow::{Context, Result};
use hdrhistogram::Histogram;
use std::path::{Path, PathBuf};

/// What the numbers were measured on.
pub struct Machine {
    pub cpu: String,
    pub cores: usize,
    pub kernel: String,
    /// Where the measured processes ran.
    pub placement: String,
}

impl Machine {
    pub fn detect() -> Self {
        let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
        let cpu = cpuinfo
            .lines()
            .find_map(|l| {
                let (key, value) = l.split_once(':')?;
                (key.trim() == "model name").then(|| value.trim().to_string())
            })
            .unwrap_or_else(|| "unknown CPU".into());
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        Self {
            cpu,
            cores,
            kernel: kernel(),
            placement: "placed by the scheduler".into(),
        }
    }

    pub fn describe(&self) -> String {
        format!(
            "CPU: {} ({} cores available), kernel: {}; {}",
            self.cpu, self.cores, self.kernel, self.placement
        )
    }
}

/// `sysname release`, e.g. `Linux 6.18.2`.
fn kernel() -> String {
    // SAFETY: uname fills a plain-data struct of fixed-size C strings.
    let mut u: libc::utsname = unsafe { std::mem::zeroed() };
    if unsafe { libc::uname(&mut u) } != 0 {
        return "unknown kernel".into();
    }
    let field = |f: &[libc::c_char]| {
        let bytes: Vec<u8> = f
            .iter()
            .take_while(|&&c| c != 0)
            .map(|&c| c as u8)
            .collect();
        String::from_utf8_lossy(&bytes).into_owned()
    };
    format!("{} {}", field(&u.sysname), field(&u.release))
}

/// Latency percentiles, ns.
#[derive(Debug, Clone, Copy)]
pub struct Percentiles {
    pub p50_ns: u64,
    pub p90_ns: u64,
    pub p99_ns: u64,
    pub p999_ns: u64,
    pub max_ns: u64,
}

/// A histogram for latencies from 1 ns to 60 s at 3 significant digits.
pub fn histogram() -> Histogram<u64> {
    Histogram::new_with_bounds(1, 60_000_000_000, 3).expect("valid histogram bounds")
}

pub fn percentiles(h: &Histogram<u64>) -> Percentiles {
    Percentiles {
        p50_ns: h.value_at_quantile(0.5),
        p90_ns: h.value_at_quantile(0.9),
        p99_ns: h.value_at_quantile(0.99),
        p999_ns: h.value_at_quantile(0.999),
        max_ns: h.max(),
    }
}

/// The median of `v` (the upper one of an even count); `v` must not be empty.
pub fn median(mut v: Vec<u64>) -> u64 {
    v.sort_unstable();
    v[v.len() / 2]
}

/// User plus system CPU time of a resource usage record, s.
pub fn cpu_seconds(ru: &libc::rusage) -> f64 {
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    secs(ru.ru_utime) + secs(ru.ru_stime)
}

/// Prints a bench's table and writes `<stem>.csv` and `<stem>.md` (machine, then the table)
/// into `out`.
pub fn write_results(
    out: &Path,
    stem: &str,
    machine: &Machine,
    table: &str,
    csv: &str,
) -> Result<()> {
    println!("{table}");
    std::fs::write(out.join(format!("{stem}.csv")), csv)?;
    std::fs::write(
        out.join(format!("{stem}.md")),
        format!("{}\n\n{table}\n", machine.describe()),
    )?;
    println!("wrote {}", out.join(format!("{stem}.csv")).display());
    Ok(())
}

/// The run directory the launcher left in `runs` (a bench launches one run per directory).
pub fn run_dir_in(runs: &Path) -> Result<PathBuf> {
    crate::latest_run_dir(runs).context("the launcher wrote no run directory")
}
