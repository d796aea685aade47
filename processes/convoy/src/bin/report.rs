//! `caravan-convoy-report`: the convoy's report plugin (see `caravan_convoy::report`).

fn main() -> std::process::ExitCode {
    caravan_report::plugin::main::<caravan_convoy::report::ConvoyReport>("caravan-convoy-report")
}
