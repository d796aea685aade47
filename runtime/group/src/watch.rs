//! Watching a running group from outside it: joining its shared memory, following a topic's
//! messages, noticing that the group has ended.

use crate::bad_input::bad;
use crate::clean::live_nodes;
use anyhow::{Result, anyhow};
use caravan::tap::{list_topics, open_listener, open_tap};
use clap::Args;
use iceoryx2::prelude::*;
use std::time::{Duration, Instant};

/// A `--seconds` value: finite, more than 0, at most ten years.
pub fn seconds_arg(text: &str) -> Result<Duration, String> {
    let value: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a number of seconds"))?;
    if value <= 0.0 {
        return Err(format!("'{text}': must be more than 0 seconds"));
    }
    caravan::seconds(value)
}

#[derive(Args)]
pub struct GroupArg {
    /// The group; defaults to the only running one
    #[arg(long, short, value_parser = crate::clean::group_arg)]
    pub group: Option<String>,
}

/// Joins `group`'s shared memory as a node of its own: the config and the node.
pub fn iox(group: &str) -> Result<(iceoryx2::config::Config, iceoryx2::node::Node<ipc::Service>)> {
    let config = caravan::group::config(group)?;
    let node = NodeBuilder::new()
        .config(&config)
        .signal_handling_mode(SignalHandlingMode::HandleTerminationRequests)
        .create::<ipc::Service>()
        .map_err(|e| anyhow!("cannot join group '{group}': {e:?}"))?;
    Ok((config, node))
}

/// Notices that a group has ended (no process of it but this one is alive), looking at most
/// once a second: listing nodes is too dear for every message.
pub struct GroupEnd {
    group: String,
    last_look: Instant,
}

impl GroupEnd {
    pub fn watch(group: &str) -> Self {
        Self {
            group: group.to_string(),
            last_look: Instant::now(),
        }
    }

    /// Whether the group has ended, if a second has passed since the last look; else false.
    pub fn ended(&mut self) -> Result<bool> {
        if self.last_look.elapsed() < Duration::from_secs(1) {
            return Ok(false);
        }
        self.last_look = Instant::now();
        let me = std::process::id() as i32;
        Ok(!live_nodes(&self.group)?.iter().any(|n| n.pid != me))
    }

    /// Whether every node of `group` has exited: no named node (the launcher's own, the
    /// scheduler's and the recorder's, and watchers like this one, have no name) but this
    /// process's is alive. The launcher may still be finishing its recording.
    pub fn nodes_gone(group: &str) -> Result<bool> {
        let me = std::process::id() as i32;
        Ok(!live_nodes(group)?
            .iter()
            .any(|n| n.pid != me && !n.name.is_empty()))
    }
}

/// Calls `each` for every message on `topic` until it returns true, `limit` passes, the group
/// ends (looked at once a second) or Ctrl-C.
pub fn follow(
    group: &str,
    topic: &str,
    limit: Option<Duration>,
    mut each: impl FnMut(&caravan::Header, serde_json::Value) -> bool,
) -> Result<()> {
    let (config, node) = iox(group)?;
    let opened = (|| -> Result<_> {
        let info = list_topics(&config, true)?
            .into_iter()
            .find(|t| t.name == topic)
            .ok_or_else(|| bad(format!("group '{group}' has no topic '{topic}'")))?;
        Ok((
            open_tap(&node, topic, &info.type_name)?,
            open_listener(&node, topic)?,
        ))
    })();
    let (tap, listener) = match opened {
        Ok(opened) => opened,
        // A group that ends while we join it takes its topics with it: that is its end, not
        // a topic we were wrong about. (Its launcher may live on a while to finish the
        // recording, so its nodes are what is looked at.)
        Err(_) if GroupEnd::nodes_gone(group).unwrap_or(false) => {
            eprintln!("caravan: group '{group}' has ended");
            return Ok(());
        }
        Err(e) => return Err(e),
    };
    let waitset = WaitSetBuilder::new()
        .signal_handling_mode(SignalHandlingMode::HandleTerminationRequests)
        .create::<ipc::Service>()
        .map_err(|e| anyhow!("{e:?}"))?;
    let _guard = waitset
        .attach_notification(&listener)
        .map_err(|e| anyhow!("{e:?}"))?;
    let end = limit.map(|l| Instant::now() + l);
    let mut batch = Vec::new();
    let mut group_end = GroupEnd::watch(group);
    loop {
        let wait = end.map_or(Duration::from_secs(1), |e| {
            e.saturating_duration_since(Instant::now())
                .min(Duration::from_secs(1))
        });
        let result = waitset
            .wait_and_process_once_with_timeout(|_| CallbackProgression::Continue, wait)
            .map_err(|e| anyhow!("{e:?}"))?;
        if !matches!(
            result,
            iceoryx2::waitset::WaitSetRunResult::AllEventsHandled
        ) {
            return Ok(());
        }
        let _ = listener.try_wait(|_| {});
        // Looked at before draining, so that what was published before the end is printed.
        let ended = group_end.ended()?;
        tap.drain(&mut batch)?;
        for m in batch.drain(..) {
            if each(&m.header, m.json()?) {
                return Ok(());
            }
        }
        if end.is_some_and(|e| Instant::now() >= e) {
            return Ok(());
        }
        if ended {
            eprintln!("caravan: group '{group}' has ended");
            return Ok(());
        }
    }
}

/// Records `group`'s topics matching `patterns` to `output` until `seconds` pass (if given),
/// the group ends or Ctrl-C; says so on stderr when the group ended.
pub fn record(
    group: &str,
    output: &std::path::Path,
    patterns: &[String],
    seconds: Option<Duration>,
) -> Result<caravan_record::Recording> {
    let config = caravan::group::config(group)?;
    let mut recorder = caravan_record::Recorder::create(
        &config,
        output,
        patterns,
        false,
        &caravan_record::recorder::RecordingMeta {
            metadata: caravan_record::recorder::run_metadata(
                &caravan_record::recorder::command_arguments(),
                None,
                Some(caravan::wall_clock_ns()),
            ),
            launch_file: None,
        },
    )?;
    let end = seconds.map(|s| Instant::now() + s);
    let mut group_end = GroupEnd::watch(group);
    let mut ended = false;
    crate::run::driver::record_until(
        &config,
        &mut recorder,
        SignalHandlingMode::HandleTerminationRequests,
        |_| {
            // The group's end stops the recording too.
            ended = ended || group_end.ended().unwrap_or(false);
            ended || end.is_some_and(|e| Instant::now() >= e)
        },
    )?;
    if ended {
        eprintln!("caravan: group '{group}' has ended");
    }
    recorder.finish()
}
