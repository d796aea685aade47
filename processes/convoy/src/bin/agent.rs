//! `caravan-convoy-agent`: a convoy robot's controller (see `caravan_convoy::agent::node`).

use caravan_convoy::agent::node;

fn main() -> std::process::ExitCode {
    caravan::node_main("caravan-convoy-agent", node::setup, node::run)
}
