//! The launch directory's world files parse, and their survey lines have the lengths their
//! comments promise (1.5–2.05 m, like the reference's map-scale checks).

use std::path::PathBuf;

fn world(name: &str) -> caravan_world::World {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../launch/convoy/worlds")
        .join(name);
    caravan_world::load_world(&path).unwrap()
}

#[test]
fn shipped_worlds_have_surveys_of_reference_length() {
    for (name, expected) in [("lab.toml", [2.025, 1.825]), ("hall.toml", [1.925, 1.975])] {
        let w = world(name);
        let lengths: Vec<f64> = w
            .surveys
            .iter()
            .map(|s| w.survey_length(s).unwrap())
            .collect();
        assert_eq!(lengths.len(), 2, "{name}");
        for (got, want) in lengths.iter().zip(expected) {
            assert!((got - want).abs() < 1e-6, "{name}: {got} vs {want}");
        }
    }
}
