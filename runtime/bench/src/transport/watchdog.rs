//! The bench's guard against a measurement that hangs.

use super::Kind;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Ends the whole bench if a measurement makes no progress for a long time (a lost message on
/// a transport that waits without a timeout), so that it never hangs a test or CI.
pub struct Watchdog {
    done: Arc<AtomicBool>,
    thread: std::thread::JoinHandle<()>,
}

impl Watchdog {
    const STALL: Duration = Duration::from_secs(60);

    pub fn start(alive: Arc<AtomicU64>, child: u32, kind: Kind, bytes: usize) -> Self {
        let done = Arc::new(AtomicBool::new(false));
        let flag = done.clone();
        let thread = std::thread::spawn(move || {
            let mut last = (u64::MAX, Instant::now());
            while !flag.load(Ordering::Relaxed) {
                let now = alive.load(Ordering::Relaxed);
                if now != last.0 {
                    last = (now, Instant::now());
                } else if last.1.elapsed() > Self::STALL {
                    eprintln!(
                        "caravan: {} {bytes} B made no progress for {:?}; giving up",
                        kind.name(),
                        Self::STALL
                    );
                    // SAFETY: signalling our own child.
                    unsafe { libc::kill(child as i32, libc::SIGKILL) };
                    std::process::exit(2);
                }
                std::thread::park_timeout(Duration::from_millis(200));
            }
        });
        Self { done, thread }
    }

    pub fn stop(self) {
        self.done.store(true, Ordering::Relaxed);
        self.thread.thread().unpark();
        let _ = self.thread.join();
    }
}
