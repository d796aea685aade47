//! Logging: Caravan's processes log through `tracing`, and iceoryx2's own messages are routed
//! into it (target `iceoryx2`), so one level setting governs both and every line says which
//! process and library it came from.
//!
//! The level comes from `CARAVAN_LOG` (`error`, `warn`, `info`, `debug`, `trace`, or a
//! `tracing` filter such as `warn,iceoryx2=error`); the default is `warn,zenoh=error,rustdds=error,ros2_client=error`. Lines go to standard
//! error, which the launcher keeps in the run directory's logs.

use iceoryx2::prelude::LogLevel;
use std::sync::{Once, OnceLock};
use tracing_subscriber::Layer;
use tracing_subscriber::layer::SubscriberExt;
use tracing_subscriber::util::SubscriberInitExt;

/// The environment variable that sets the level.
pub const LEVEL_VAR: &str = "CARAVAN_LOG";

/// Forwards iceoryx2's log calls to `tracing`.
struct IceoryxToTracing;

impl iceoryx2_log::Log for IceoryxToTracing {
    fn log(&self, level: LogLevel, origin: std::fmt::Arguments, message: std::fmt::Arguments) {
        match level {
            LogLevel::Trace => tracing::trace!(target: "iceoryx2", "{origin}: {message}"),
            LogLevel::Debug => tracing::debug!(target: "iceoryx2", "{origin}: {message}"),
            LogLevel::Info => tracing::info!(target: "iceoryx2", "{origin}: {message}"),
            LogLevel::Warn => tracing::warn!(target: "iceoryx2", "{origin}: {message}"),
            LogLevel::Error | LogLevel::Fatal => {
                tracing::error!(target: "iceoryx2", "{origin}: {message}")
            }
        }
    }
}

static ICEORYX_TO_TRACING: IceoryxToTracing = IceoryxToTracing;
static INIT: Once = Once::new();

/// iceoryx2's level for a filter: the most verbose level the filter could let through, so
/// iceoryx2 does not format what `tracing` would drop anyway.
fn iceoryx_level(filter: &tracing_subscriber::EnvFilter) -> LogLevel {
    use tracing_subscriber::filter::LevelFilter;
    match filter.max_level_hint() {
        Some(LevelFilter::TRACE) | None => LogLevel::Trace,
        Some(LevelFilter::DEBUG) => LogLevel::Debug,
        Some(LevelFilter::INFO) => LogLevel::Info,
        Some(LevelFilter::WARN) => LogLevel::Warn,
        Some(LevelFilter::ERROR) => LogLevel::Error,
        Some(_) => LogLevel::Fatal,
    }
}

/// Warnings and worse; zenoh's only when they are errors (its warnings are about its own
/// start-up, such as a host not reachable yet, which the launcher reports itself), and the
/// ROS 2 bridge's DDS stack's too (RustDDS warns of every datagram over 1,500 bytes, and
/// ros2-client of an unset `ROS_DISTRO`).
const DEFAULT_FILTER: &str = "warn,zenoh=error,rustdds=error,ros2_client=error";

/// Installs the logger once per process, naming the process in each line (`name`, e.g. the
/// node's or `caravan`). A bad `CARAVAN_LOG` falls back to `warn` with a warning.
pub fn init(name: &str) {
    INIT.call_once(|| {
        let text = std::env::var(LEVEL_VAR).unwrap_or_default();
        let parsed = if text.trim().is_empty() {
            Ok(tracing_subscriber::EnvFilter::new(DEFAULT_FILTER))
        } else {
            tracing_subscriber::EnvFilter::try_new(text.trim())
        };
        let (filter, bad) = match parsed {
            Ok(f) => (f, None),
            Err(e) => (tracing_subscriber::EnvFilter::new(DEFAULT_FILTER), Some(e)),
        };
        iceoryx2::prelude::set_log_level(iceoryx_level(&filter));
        iceoryx2::prelude::set_logger(&ICEORYX_TO_TRACING);
        let name = name.to_string();
        let print = tracing_subscriber::fmt::layer()
            .with_writer(std::io::stderr)
            .without_time()
            .with_ansi(false)
            .fmt_fields(tracing_subscriber::fmt::format::DefaultFields::new())
            .event_format(Format { name })
            .with_filter(filter);
        let tap = Tap.with_filter(tracing_subscriber::EnvFilter::new(TAP_FILTER));
        let _ = tracing_subscriber::registry()
            .with(print)
            .with(tap)
            .try_init();
        if let Some(e) = bad {
            tracing::warn!("{LEVEL_VAR}='{text}' is not a log filter ({e}); logging at warn");
        }
    });
}

/// What [`tap`] hears, whatever the level printed: zenoh's reasons for a failed connection,
/// which it logs below the printed level (a refused certificate on the listening side, a
/// failed dial on the dialling side).
pub const TAP_FILTER: &str =
    "off,zenoh_link_commons::quic=warn,zenoh::net::runtime::orchestrator=debug";

/// A function given each event [`TAP_FILTER`] lets through: its target and its message.
pub type Listener = Box<dyn Fn(&str, &str) + Send + Sync>;

static TAPPED: OnceLock<Listener> = OnceLock::new();

/// Hands the events of [`TAP_FILTER`] to `listener` from now on (once per process; a second
/// call is ignored). The launcher of a host uses it to name the peer of a failed TLS
/// handshake, which zenoh only logs.
pub fn tap(listener: Listener) {
    let _ = TAPPED.set(listener);
}

/// The layer behind [`tap`].
struct Tap;

impl<S: tracing::Subscriber> Layer<S> for Tap {
    fn on_event(&self, event: &tracing::Event<'_>, _: tracing_subscriber::layer::Context<'_, S>) {
        if let Some(listener) = TAPPED.get() {
            let mut message = Message(String::new());
            event.record(&mut message);
            listener(event.metadata().target(), &message.0);
        }
    }
}

/// An event's `message` field as text.
struct Message(String);

impl tracing::field::Visit for Message {
    fn record_debug(&mut self, field: &tracing::field::Field, value: &dyn std::fmt::Debug) {
        if field.name() == "message" {
            self.0 = format!("{value:?}");
        }
    }
}

/// `caravan[physics] WARN iceoryx2: message`: short, and says who spoke.
struct Format {
    name: String,
}

impl<S, N> tracing_subscriber::fmt::FormatEvent<S, N> for Format
where
    S: tracing::Subscriber + for<'a> tracing_subscriber::registry::LookupSpan<'a>,
    N: for<'a> tracing_subscriber::fmt::FormatFields<'a> + 'static,
{
    fn format_event(
        &self,
        ctx: &tracing_subscriber::fmt::FmtContext<'_, S, N>,
        mut writer: tracing_subscriber::fmt::format::Writer<'_>,
        event: &tracing::Event<'_>,
    ) -> std::fmt::Result {
        let meta = event.metadata();
        write!(
            writer,
            "caravan[{}] {} {}: ",
            self.name,
            meta.level(),
            meta.target()
        )?;
        ctx.field_format().format_fields(writer.by_ref(), event)?;
        writeln!(writer)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iceoryx_level_follows_the_most_verbose_directive() {
        let level = |f: &str| iceoryx_level(&tracing_subscriber::EnvFilter::new(f)) as u8;
        assert_eq!(level("warn"), LogLevel::Warn as u8);
        assert_eq!(level("error"), LogLevel::Error as u8);
        assert_eq!(level("warn,iceoryx2=debug"), LogLevel::Debug as u8);
        assert_eq!(level("off"), LogLevel::Fatal as u8);
    }
}
