//! What a node's check tells the launcher besides good or bad: the robots a simulation holds
//! and the robot a node serves. No process sees both (a drive's `robot` and the physics'
//! `robots` list), so the launcher compares them before anything starts: a drive for robot 9
//! of a one-robot simulation is refused, naming its `robot`, instead of never moving.

use crate::NodeIdentity;

/// What a fact's line on a check's standard output starts with.
pub const PREFIX: &str = "caravan-fact";

/// One fact a node states in its check.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fact {
    /// The node simulates robots 0 to n − 1 (the physics).
    Simulates(usize),
    /// The node serves robot i (its `robot` param): one of those simulated.
    Serves(usize),
}

impl NodeIdentity {
    /// In a check ([`crate::check_only`]), states that this node simulates robots 0 to
    /// `count` − 1; otherwise does nothing.
    pub fn simulates_robots(&self, count: usize) {
        self.state(Fact::Simulates(count));
    }

    /// In a check, states that this node serves robot `index` (its key `robot`), which the
    /// launcher then finds among the robots simulated, if any node states those.
    pub fn serves_robot(&self, index: usize) {
        self.state(Fact::Serves(index));
    }

    fn state(&self, fact: Fact) {
        if crate::check_only() {
            let (what, n) = match fact {
                Fact::Simulates(n) => ("simulates", n),
                Fact::Serves(i) => ("serves", i),
            };
            println!("{PREFIX} {} {what} {n}", self.name);
        }
    }
}

/// The facts on a check's standard output, each with the node that stated it.
pub fn read(stdout: &str) -> Vec<(String, Fact)> {
    stdout
        .lines()
        .filter_map(|line| {
            let mut words = line.strip_prefix(PREFIX)?.split_whitespace();
            let (node, what, n) = (words.next()?, words.next()?, words.next()?.parse().ok()?);
            let fact = match what {
                "simulates" => Fact::Simulates(n),
                "serves" => Fact::Serves(n),
                _ => return None,
            };
            Some((node.to_string(), fact))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn facts_are_read_back_with_their_node_and_other_lines_ignored() {
        let out = "hello\ncaravan-fact physics simulates 5\ncaravan-fact drive serves 9\n\
                   caravan-fact drive flies 2\ncaravan-fact x serves many\n";
        assert_eq!(
            read(out),
            vec![
                ("physics".to_string(), Fact::Simulates(5)),
                ("drive".to_string(), Fact::Serves(9))
            ]
        );
    }
}
