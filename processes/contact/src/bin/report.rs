//! `caravan-contact-report`: the `contact` report section (see `caravan_contact::report`).

fn main() -> std::process::ExitCode {
    caravan_report::plugin::main::<caravan_contact::report::ContactReport>("caravan-contact-report")
}
