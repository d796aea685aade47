//! Terrain specs under mutation fuzzing: the shipped specs (launch/tracked/terrains), edited
//! 1 to 4 times at random (`caravan_report::fuzz`), must parse and generate a terrain or give
//! an error, never panic. CI runs 2,000; `PROPTEST_CASES=1000000 cargo nextest run --release
//! -p caravan-tracked -E 'test(fuzz_terrain)'` is the long run (docs/reliability.md).

use super::parse_spec;
use crate::rse::generate;
use proptest::prelude::*;

fn shipped() -> Vec<String> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../launch/tracked/terrains");
    let mut specs: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .filter(|e| e.path().extension().is_some_and(|x| x == "toml"))
        .map(|e| std::fs::read_to_string(e.path()).unwrap())
        .collect();
    specs.sort();
    assert!(specs.len() >= 4, "the shipped terrain specs");
    specs
}

fn cases() -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2_000)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn fuzz_terrain_specs_never_panic(pick in any::<usize>(), seed in any::<u64>()) {
        let specs = shipped();
        let text = caravan_report::fuzz::mutate(&specs[pick % specs.len()], seed);
        // A spec that passes its checks must also make a terrain.
        if let Ok(spec) = parse_spec(&text) {
            let grid = generate(&spec, seed);
            prop_assert!(grid.heights.iter().all(|h| h.is_finite()), "{text}");
        }
    }
}
