//! The launch-file loader under mutation fuzzing: shipped launch files, edited at random
//! (`caravan_report::fuzz`), must load or give problems, never panic. CI runs 2,000 inputs;
//! `PROPTEST_CASES=1000000 cargo nextest run --release -p caravan-launch fuzz_launch` is the
//! long run (docs/reliability.md).

use super::{BASE, resolve};
use crate::load::load;
use caravan_report::fuzz::mutate;
use proptest::prelude::*;

const SHIPPED: &[&str] = &[
    BASE,
    include_str!("../../../../launch/pingpong.toml"),
    include_str!("../../../../launch/convoy/convoy.toml"),
    include_str!("../../../../launch/convoy/convoy-wlan.toml"),
    include_str!("../../../../launch/uav/encounter.toml"),
    include_str!("../../../../launch/tracked/terrain.toml"),
    include_str!("../../../../launch/contact/push.toml"),
];

fn config() -> ProptestConfig {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2000);
    ProptestConfig {
        cases,
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn fuzz_launch_loader_never_panics(pick in any::<usize>(), seed in any::<u64>()) {
        // One file for all cases: a million cases must not make a million directories.
        thread_local!(static FILE: std::path::PathBuf = super::temp_dir().join("launch.toml"));
        let path = FILE.with(|f| f.clone());
        std::fs::write(&path, mutate(SHIPPED[pick % SHIPPED.len()], seed)).unwrap();
        let _ = load(&path, &[], &resolve);
    }
}
