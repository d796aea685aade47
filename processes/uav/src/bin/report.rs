//! `caravan-uav-report`: the `uav` report section (see `caravan_uav::report`).

fn main() -> std::process::ExitCode {
    caravan_report::plugin::main::<caravan_uav::report::UavReport>("caravan-uav-report")
}
