//! `caravan-imu-report`: the `imu` report section (see `caravan_imu::report`).

fn main() -> std::process::ExitCode {
    caravan_report::plugin::main::<caravan_imu::report::ImuReport>("caravan-imu-report")
}
