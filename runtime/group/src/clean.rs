//! Finding running groups and removing what dead ones left behind (`caravan clean`).

use crate::bad_input::bad;
use anyhow::{Result, anyhow};
use iceoryx2::node::{NodeState, NodeView};
use iceoryx2::prelude::*;

/// A live node of a group: its name, process id and iceoryx2 id.
pub struct LiveNode {
    pub name: String,
    pub pid: i32,
    pub id: iceoryx2::identifiers::UniqueNodeId,
}

/// The nodes of `group` whose processes are alive.
pub fn live_nodes(group: &str) -> Result<Vec<LiveNode>> {
    let config = caravan::group::config(group)?;
    let mut nodes = Vec::new();
    iceoryx2::node::Node::<ipc::Service>::list(&config, |state| {
        if let NodeState::Alive(view) = state
            && let Some(details) = view.details()
        {
            nodes.push(LiveNode {
                name: details.name().to_string(),
                pid: details.process_id().value(),
                id: *view.id(),
            });
        }
        CallbackProgression::Continue
    })
    .map_err(|e| anyhow!("cannot list the nodes of group '{group}': {e:?}"))?;
    nodes.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(nodes)
}

/// The lock a launcher holds on its group's name for as long as it runs: taking it is atomic,
/// so of two launches of one group started at the same instant exactly one gets it. The lock
/// is released when the file is closed, including when the launcher dies. Dropping it removes
/// the group's files in the temporary directory (the lock and the launcher's iceoryx2 config).
pub struct GroupLock {
    _file: std::fs::File,
    path: std::path::PathBuf,
    group: String,
}

impl Drop for GroupLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(global_config_path(&self.group));
        // Unlinked while still held, so no other launcher holds a lock on this file.
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Where the launcher of `group` writes the iceoryx2 config it uses as its global one.
pub fn global_config_path(group: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("caravan-group-{group}.iceoryx2.toml"))
}

/// Takes `group`'s lock, or `None` when another launcher holds it.
pub fn lock_group(group: &str) -> Result<Option<GroupLock>> {
    use std::os::unix::fs::OpenOptionsExt;
    use std::os::unix::io::AsRawFd;
    let path = lock_path(group);
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .mode(0o600)
        .open(&path)
        .map_err(|e| anyhow!("cannot open the group lock {}: {e}", path.display()))?;
    // SAFETY: flock on a descriptor this function owns.
    if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } != 0 {
        let e = std::io::Error::last_os_error();
        if e.raw_os_error() == Some(libc::EWOULDBLOCK) {
            return Ok(None);
        }
        return Err(anyhow!("cannot lock {}: {e}", path.display()));
    }
    Ok(Some(GroupLock {
        _file: file,
        path,
        group: group.to_string(),
    }))
}

/// Whether a launcher holds `group`'s lock (looked at without taking it for good or removing
/// the file: `caravan clean` may be about another group).
fn lock_is_held(group: &str) -> bool {
    use std::os::unix::io::AsRawFd;
    let Ok(file) = std::fs::File::open(lock_path(group)) else {
        return false;
    };
    // SAFETY: flock on a descriptor this function owns; closing it releases the lock.
    unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_SH | libc::LOCK_NB) != 0 }
}

fn lock_path(group: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("caravan-group-{group}.lock"))
}

/// Groups with a lock file in the temporary directory, held or left by a killed launcher.
fn groups_with_locks() -> Vec<String> {
    std::fs::read_dir(std::env::temp_dir())
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().to_string();
            let group = name.strip_prefix("caravan-group-")?.strip_suffix(".lock")?;
            caravan::group::validate_name(group).ok()?;
            Some(group.to_string())
        })
        .collect()
}

pub fn group_is_running(group: &str) -> Result<bool> {
    Ok(caravan::group::groups_with_resources()
        .iter()
        .any(|g| g == group)
        && !live_nodes(group)?.is_empty())
}

/// Removes the resources of `group` if none of its processes is alive.
pub fn remove_stale(group: &str) -> Result<usize> {
    if !live_nodes(group)?.is_empty() {
        return Ok(0);
    }
    Ok(caravan::group::remove_resources(group)?)
}

/// Groups with a live node, for commands that act on "the only running group".
pub fn running_groups() -> Result<Vec<String>> {
    let mut out = Vec::new();
    for g in caravan::group::groups_with_resources() {
        if !live_nodes(&g)?.is_empty() {
            out.push(g);
        }
    }
    Ok(out)
}

/// The group named, or the only running one.
pub fn choose_group(named: Option<&str>) -> Result<String> {
    let running = running_groups()?;
    if let Some(g) = named {
        // Joining a group that is not running would create its shared memory.
        if running.iter().any(|r| r == g) {
            return Ok(g.to_string());
        }
        let which = match running.as_slice() {
            [] => "no Caravan group is running".to_string(),
            list => format!("running: {}", list.join(", ")),
        };
        return Err(bad(format!("no group '{g}' is running ({which})")));
    }
    match running.as_slice() {
        [one] => Ok(one.clone()),
        [] => Err(bad("no Caravan group is running")),
        many => Err(bad(format!(
            "{} groups are running ({}); choose one with --group",
            many.len(),
            many.join(", ")
        ))),
    }
}

/// A `--group` value: a usable group name (so it cannot reach outside Caravan's files).
pub fn group_arg(text: &str) -> Result<String, String> {
    caravan::group::validate_name(text)?;
    Ok(text.to_string())
}

#[derive(clap::Args)]
pub struct CleanArgs {
    /// The group to clean
    #[arg(long, short, conflicts_with = "all", value_parser = group_arg)]
    pub group: Option<String>,
    /// Clean every group none of whose processes is alive
    #[arg(long)]
    pub all: bool,
}

/// `caravan clean`: removes the resources of the group named, of the only stale group, or
/// (`--all`) of every stale group. A running group is never touched.
pub fn clean(args: &CleanArgs) -> Result<()> {
    let mut stale = Vec::new();
    let with_memory = caravan::group::groups_with_resources();
    let mut groups = with_memory.clone();
    groups.extend(groups_with_locks());
    groups.sort();
    groups.dedup();
    for group in groups {
        // A launcher holds its lock from before its processes start (while it waits for
        // other hosts, say) until after they end; one killed leaves only the file.
        let running = if with_memory.contains(&group) {
            !live_nodes(&group)?.is_empty()
        } else {
            lock_is_held(&group)
        };
        match &args.group {
            Some(g) if *g != group => {}
            // Bad input (exit 2): the user named a group that is not theirs to clean yet.
            Some(g) if running => {
                return Err(bad(format!("group '{g}' is running; stop it first")));
            }
            _ if running => {}
            _ => stale.push(group),
        }
    }
    let chosen = match (&args.group, args.all, stale.as_slice()) {
        (Some(g), _, []) => {
            println!("group '{g}' left nothing to clean");
            return Ok(());
        }
        (_, _, []) => {
            println!("nothing to clean");
            return Ok(());
        }
        // Which to clean is the user's choice: bad input (exit 2) until they make it.
        (None, false, [_, _, ..]) => {
            return Err(bad(format!(
                "{} groups left shared memory or a lock behind ({}); name one with --group, or clean them all with --all",
                stale.len(),
                stale.join(", ")
            )));
        }
        _ => stale,
    };
    for group in chosen {
        let n = caravan::group::remove_resources(&group)?;
        // A dead launcher's lock and config go too (taking the lock proves none holds it).
        drop(lock_group(&group)?);
        println!("removed {n} stale entries of group '{group}', and its lock and config");
    }
    Ok(())
}
