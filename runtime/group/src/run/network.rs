//! The group's network for its nodes (`CARAVAN_NETWORK`): process hosts, CPU slowdowns and
//! one profile per ordered pair of linked hosts, resolved from the launch file's patterns.

use caravan::network::{LinkProfile, Network};
use caravan_launch::model::{LaunchFile, glob_match};

/// `None` when the launch file declares no links and no CPU slowdowns.
pub fn resolve(lf: &LaunchFile) -> Option<Network> {
    let cpu_slowdown: std::collections::BTreeMap<String, f64> = lf
        .hosts
        .iter()
        .filter_map(|(name, h)| Some((name.clone(), h.cpu_slowdown?)))
        .collect();
    if lf.links.is_empty() && cpu_slowdown.is_empty() {
        return None;
    }
    let mut links = Vec::new();
    for from in lf.hosts.keys() {
        for to in lf.hosts.keys() {
            if from == to {
                continue;
            }
            // The first link whose patterns match the pair, either way round.
            let Some(spec) = lf.links.iter().find(|l| {
                let [a, b] = &l.between;
                (glob_match(a, from) && glob_match(b, to))
                    || (glob_match(b, from) && glob_match(a, to))
            }) else {
                continue;
            };
            let ns = |d: std::time::Duration| d.as_nanos() as u64;
            links.push(LinkProfile {
                from: from.clone(),
                to: to.clone(),
                latency_ns: ns(spec.latency),
                jitter_ns: ns(spec.jitter),
                jitter: spec.distribution,
                loss: spec.loss,
                spike_probability: spec.spike_probability,
                spike_ns: [ns(spec.spike[0]), ns(spec.spike[1])],
                bandwidth_bps: spec.bandwidth_bps,
            });
        }
    }
    Some(Network {
        seed: lf.group.seed,
        hosts: lf
            .processes
            .iter()
            .map(|p| (p.name.clone(), p.host.clone()))
            .chain(lf.left_out.clone())
            .collect(),
        cpu_slowdown,
        links,
    })
}
