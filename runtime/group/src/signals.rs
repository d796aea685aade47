//! Ctrl-C and SIGTERM, watched from the moment a launcher holds its group's lock until its run
//! ends: a signal that comes before the group starts (while the launcher waits for the other
//! hosts, or checks its processes) is held for the run, never the default action that would
//! end the launcher without removing its group's lock and config.

use crossbeam::channel::{Receiver, bounded, select, unbounded};

/// The launcher's watch on Ctrl-C and SIGTERM. Dropping it stops the watch.
pub struct Signals {
    received: Receiver<i32>,
    handle: signal_hook::iterator::Handle,
}

impl Signals {
    pub fn watch() -> anyhow::Result<Self> {
        use signal_hook::consts::{SIGINT, SIGTERM};
        let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM])
            .map_err(|e| anyhow::anyhow!("cannot watch for Ctrl-C: {e}"))?;
        let handle = signals.handle();
        let (tx, received) = unbounded();
        std::thread::spawn(move || {
            for signal in signals.forever() {
                if tx.send(signal).is_err() {
                    break;
                }
            }
        });
        Ok(Self { received, handle })
    }

    /// Each signal, in the order received; the channel closes when the watch stops.
    pub fn received(&self) -> Receiver<i32> {
        self.received.clone()
    }

    /// Runs `wait`, handing the first signal that comes before it returns to `on_signal` (on
    /// another thread), which is to make `wait` return. Returns what `wait` returned, and the
    /// signal taken meanwhile, if any: one that came as `wait` returned by itself is taken
    /// too, and the caller must still act on it.
    pub fn during<T>(
        &self,
        on_signal: impl FnOnce(i32) + Send,
        wait: impl FnOnce() -> T,
    ) -> (T, Option<i32>) {
        let (done, finished) = bounded::<()>(0);
        std::thread::scope(|s| {
            let watcher = s.spawn(|| {
                select! {
                    recv(self.received) -> signal => signal.ok().inspect(|&signal| on_signal(signal)),
                    recv(finished) -> _ => None,
                }
            });
            let out = wait();
            drop(done);
            (
                out,
                watcher.join().expect("the signal watcher does not panic"),
            )
        })
    }
}

impl Drop for Signals {
    fn drop(&mut self) {
        self.handle.close();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_signal_during_a_wait_is_handed_over_and_one_after_it_is_kept() {
        let signals = Signals::watch().unwrap();
        let (tx, rx) = bounded(1);
        let (got, taken) = signals.during(
            move |s| tx.send(s).unwrap(),
            || {
                // SAFETY: raising a signal this process watches.
                unsafe { libc::raise(libc::SIGTERM) };
                rx.recv().unwrap()
            },
        );
        assert_eq!((got, taken), (libc::SIGTERM, Some(libc::SIGTERM)));
        // A wait that ends by itself leaves the next signal for the run.
        let ((), taken) = signals.during(|_| panic!("no signal came during this wait"), || ());
        assert_eq!(taken, None);
        unsafe { libc::raise(libc::SIGINT) };
        assert_eq!(signals.received().recv().unwrap(), libc::SIGINT);
    }
}
