//! `caravan-convoy-monitor`: the convoy's gaps and cross-track errors, live (see
//! `caravan_convoy::monitor`).

use caravan_convoy::monitor;

fn main() -> std::process::ExitCode {
    caravan::node_main("caravan-convoy-monitor", monitor::setup, monitor::run)
}
