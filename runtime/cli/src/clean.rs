//! Finding running groups and removing what dead ones left behind (`caravan clean`).

use anyhow::{Result, anyhow};
use iceoryx2::node::{NodeState, NodeView};
use iceoryx2::prelude::*;

/// A live node of a group: its name and process id.
pub struct LiveNode {
    pub name: String,
    pub pid: i32,
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
            });
        }
        CallbackProgression::Continue
    })
    .map_err(|e| anyhow!("cannot list the nodes of group '{group}': {e:?}"))?;
    nodes.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(nodes)
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
    if let Some(g) = named {
        return Ok(g.to_string());
    }
    let running = running_groups()?;
    match running.as_slice() {
        [one] => Ok(one.clone()),
        [] => Err(anyhow!("no Caravan group is running")),
        many => Err(anyhow!(
            "{} groups are running ({}); choose one with --group",
            many.len(),
            many.join(", ")
        )),
    }
}

/// `caravan clean`: sweeps every group without a live process.
pub fn clean() -> Result<()> {
    let mut any = false;
    for group in caravan::group::groups_with_resources() {
        if live_nodes(&group)?.is_empty() {
            let n = caravan::group::remove_resources(&group)?;
            println!("removed {n} stale entries of group '{group}'");
            any = true;
        } else {
            println!("group '{group}' is running; left alone");
        }
    }
    if !any {
        println!("nothing to clean");
    }
    Ok(())
}
