//! Spin, then park: a node may look for its next message or grant for a bounded time before it
//! sleeps.
//!
//! A sleeping process is woken through the kernel (iceoryx2's event is a Unix datagram), which
//! costs ~25 µs on a VM, more than a Unix socket read. When the next message is expected within
//! microseconds (a request answered at once, a lockstep hand-off), looking for it for a while
//! (a lockstep node in the grant topic's shared memory, a realtime one with non-blocking reads
//! of its listener) finds it without any wake-up. The look is bounded by the node's `spin`
//! budget (launch key `spin`, at most [`MAX_SPIN`]); after it the node parks as before, so an
//! idle node costs one budget of CPU per wake-up and nothing in between. The default budget is
//! zero: no spinning.

use crate::Error;
use std::time::{Duration, Instant};

/// The longest spin budget a node may have: spinning longer than this costs more CPU than any
/// wake-up it could save.
pub const MAX_SPIN: Duration = Duration::from_millis(1);

/// Polls between two `sched_yield`s, so a spinning process lets others on its core run.
const POLLS_PER_YIELD: u32 = 32;

/// Parses a spin budget such as `"50us"`: a duration of at most [`MAX_SPIN`].
pub fn parse_spin(text: &str) -> Result<Duration, Error> {
    let spin = crate::parse_duration(text)?;
    if spin > MAX_SPIN {
        return Err(Error::Config(format!(
            "spin '{text}' is longer than the {MAX_SPIN:?} a node may spin before it sleeps"
        )));
    }
    Ok(spin)
}

/// A spin budget as [`parse_spin`] reads it back exactly (`"50000ns"`), for the environment
/// and command lines.
pub fn spin_text(spin: Duration) -> String {
    format!("{}ns", spin.as_nanos())
}

/// Calls `poll` until it yields something or `budget` has passed, whichever comes first. Always
/// polls at least once. `None`: nothing came within the budget, so the caller should park.
pub fn spin_for<T>(
    budget: Duration,
    mut poll: impl FnMut() -> Result<Option<T>, Error>,
) -> Result<Option<T>, Error> {
    let start = Instant::now();
    let mut polls: u32 = 0;
    loop {
        if let Some(found) = poll()? {
            return Ok(Some(found));
        }
        if start.elapsed() >= budget {
            return Ok(None);
        }
        polls = polls.wrapping_add(1);
        if polls.is_multiple_of(POLLS_PER_YIELD) {
            std::thread::yield_now();
        } else {
            std::hint::spin_loop();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spin_budgets_are_durations_up_to_a_millisecond() {
        assert_eq!(parse_spin("50us").unwrap(), Duration::from_micros(50));
        assert_eq!(parse_spin("0s").unwrap(), Duration::ZERO);
        assert_eq!(parse_spin("1ms").unwrap(), MAX_SPIN);
        let long = parse_spin("2ms").unwrap_err().to_string();
        assert!(long.contains("longer than"), "{long}");
        assert!(parse_spin("fast").is_err());
    }

    #[test]
    fn a_spin_written_as_text_reads_back_the_same() {
        for spin in [
            Duration::ZERO,
            Duration::from_nanos(1),
            Duration::from_micros(50),
            MAX_SPIN,
        ] {
            assert_eq!(parse_spin(&spin_text(spin)).unwrap(), spin);
        }
    }

    #[test]
    fn a_zero_budget_polls_once() {
        let mut polls = 0;
        let got: Option<()> = spin_for(Duration::ZERO, || {
            polls += 1;
            Ok(None)
        })
        .unwrap();
        assert_eq!((got, polls), (None, 1));
    }

    #[test]
    fn spinning_returns_what_the_poll_found_and_stops_there() {
        let mut polls = 0;
        let got = spin_for(Duration::from_secs(10), || {
            polls += 1;
            Ok((polls == 5).then_some(polls))
        })
        .unwrap();
        assert_eq!(got, Some(5));
    }

    #[test]
    fn spinning_gives_up_after_its_budget() {
        let budget = Duration::from_micros(200);
        let start = Instant::now();
        let got: Option<()> = spin_for(budget, || Ok(None)).unwrap();
        assert_eq!(got, None);
        assert!(start.elapsed() >= budget);
    }

    #[test]
    fn a_failing_poll_ends_the_spin_with_its_error() {
        let got: Result<Option<()>, Error> = spin_for(Duration::from_secs(10), || {
            Err(Error::Config("gone".into()))
        });
        assert!(got.is_err());
    }
}
