//! `caravan-tracked-report`: the `tracked` report section (see `caravan_tracked::report`).

fn main() -> std::process::ExitCode {
    caravan_report::plugin::main::<caravan_tracked::report::TrackedReport>("caravan-tracked-report")
}
