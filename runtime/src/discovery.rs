//! Watching a group from outside its nodes: when to look for new topics, whether any service
//! appeared or went since the last look, and waiting on listeners until a deadline. The
//! launcher's recorder and its bridge between hosts both discover a group's topics this way.

use crate::Error;
use iceoryx2::port::listener::Listener;
use iceoryx2::prelude::*;
use std::path::Path;
use std::time::{Duration, Instant, SystemTime};

/// How long until the next look for new topics: they appear as processes start, so often at
/// first (100 ms), then every second.
pub fn discovery_interval(started: Instant) -> Duration {
    if started.elapsed() < Duration::from_secs(3) {
        Duration::from_millis(100)
    } else {
        Duration::from_secs(1)
    }
}

/// The modification time of the directory iceoryx2 keeps the services' static configs in,
/// which changes whenever a service is made or removed; `None` when it cannot be read.
pub fn services_changed(config: &iceoryx2::config::Config) -> Option<SystemTime> {
    let dir = Path::new(&config.global.root_path().to_string())
        .join(config.global.service.directory.to_string());
    std::fs::metadata(dir).and_then(|m| m.modified()).ok()
}

/// Waits on `listeners` until `deadline`, calling `woken` after each wake-up and at least every
/// 250 ms (which bounds how late a stop is noticed; idle cost is 4 wake-ups/s). Returns true
/// when `woken` returned true or (with `signals` handling termination requests) on Ctrl-C,
/// false at the deadline.
/// `E` is the caller's error type, which `woken`'s errors come in (`listen_until::<anyhow::Error,
/// _>` names it where a closure's `?` leaves it open).
pub fn listen_until<E: From<Error>, F: FnMut() -> Result<bool, E>>(
    listeners: &[&Listener<ipc::Service>],
    deadline: Instant,
    signals: SignalHandlingMode,
    mut woken: F,
) -> Result<bool, E> {
    let waitset = WaitSetBuilder::new()
        .signal_handling_mode(signals)
        .create::<ipc::Service>()
        .map_err(|e| Error::transport("waitset", e))?;
    let _guards = listeners
        .iter()
        .map(|l| waitset.attach_notification(*l))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| Error::transport("waitset", e))?;
    while Instant::now() < deadline {
        let wait = deadline
            .saturating_duration_since(Instant::now())
            .min(Duration::from_millis(250));
        let result = if listeners.is_empty() {
            // Nothing to listen to yet (a WaitSet refuses to wait on nothing).
            std::thread::sleep(wait);
            iceoryx2::waitset::WaitSetRunResult::AllEventsHandled
        } else {
            waitset
                .wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, wait)
                .map_err(|e| Error::transport("waitset", e))?
        };
        for l in listeners {
            let _ = l.try_wait(|_| {});
        }
        let interrupted = !matches!(
            result,
            iceoryx2::waitset::WaitSetRunResult::AllEventsHandled
        );
        if woken()? || interrupted {
            return Ok(true);
        }
    }
    Ok(false)
}
