//! Robot indices against the robots the group simulates, from the facts the processes' checks
//! state (`caravan::facts`): a node serving robot 9 of a one-robot simulation would wait for
//! a robot that never comes (a drive that never moves, a sensor that never reads).

use caravan::facts::Fact;
use caravan_launch::model::{EntryList, EntryProblem, LaunchFile};

/// A problem for each node serving a robot no simulating node holds. Nothing is checked when
/// no process states what it simulates (its physics runs on another host, say).
pub fn served_robots_are_simulated(lf: &LaunchFile, facts: &[(String, Fact)]) -> Vec<EntryProblem> {
    let simulating: Vec<(&str, usize)> = facts
        .iter()
        .filter_map(|(node, fact)| match fact {
            Fact::Simulates(n) => Some((node.as_str(), *n)),
            Fact::Serves(_) => None,
        })
        .collect();
    let Some(&(_, most)) = simulating.iter().max_by_key(|(_, n)| *n) else {
        return Vec::new();
    };
    let who = simulating
        .iter()
        .map(|(node, n)| format!("process '{node}' simulates {}", robots(*n)))
        .collect::<Vec<_>>()
        .join(", ");
    facts
        .iter()
        .filter_map(|(node, fact)| match fact {
            Fact::Serves(i) if *i >= most => Some((node, *i)),
            _ => None,
        })
        .filter_map(|(node, i)| {
            let index = lf.processes.iter().position(|p| &p.name == node)?;
            Some(EntryProblem {
                list: EntryList::Process,
                index,
                key: Some("robot".into()),
                message: format!(
                    "process '{node}': key 'robot': robot {i} is not simulated ({who}; robots \
                     are numbered from 0)"
                ),
            })
        })
        .collect()
}

fn robots(n: usize) -> String {
    match n {
        0 => "no robot".into(),
        1 => "one robot, robot 0".into(),
        n => format!("{n} robots, 0 to {}", n - 1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_robot_past_those_simulated_is_named_with_who_simulates_them() {
        let text = "[group]\nname = \"r\"\n[[process]]\nname = \"physics\"\nexec = \"x\"\n\
                    [[process]]\nname = \"drive\"\nexec = \"x\"\n";
        let lf = caravan_launch::load::load_source(
            std::path::Path::new("launch.toml"),
            Some(text.into()),
            &[],
            &|_| Some("x".into()),
            &|_| Vec::new(),
        )
        .unwrap();
        let facts = [
            ("physics".to_string(), Fact::Simulates(1)),
            ("drive".to_string(), Fact::Serves(9)),
            ("physics".to_string(), Fact::Serves(0)),
        ];
        let problems = served_robots_are_simulated(&lf, &facts);
        assert_eq!(problems.len(), 1, "{problems:?}");
        assert_eq!(problems[0].index, 1);
        assert_eq!(problems[0].key.as_deref(), Some("robot"));
        assert!(
            problems[0].message.contains(
                "robot 9 is not simulated (process 'physics' simulates one robot, robot 0"
            ),
            "{}",
            problems[0].message
        );
        // Without a simulation stated, nothing to compare with.
        assert!(served_robots_are_simulated(&lf, &facts[1..]).is_empty());
    }
}
