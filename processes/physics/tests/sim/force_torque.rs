//! Force–torque sensors on fixed joints against statics and F = m·a.

use caravan_physics::wrench::WrenchCommand;
use caravan_physics::{Params, Simulation, load};
use std::path::Path;

fn sim(params: serde_json::Value) -> Simulation {
    let params: Params = caravan::parse_params("physics", &params).unwrap();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/robots");
    load(&params, &dir, 1_000_000).unwrap()
}

/// A 10 N push along the cube's x, above its centre, until replaced.
fn push_10_n() -> WrenchCommand {
    WrenchCommand {
        link: "cube".into(),
        in_link_frame: true,
        point: [0.0, 0.0, 0.15 * 0.2],
        force: [10.0, 0.0, 0.0],
        torque: [0.0; 3],
        duration_s: 0.0,
    }
}

fn close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() <= tol)
}

/// A 1 kg mass hangs from a post by a fixed joint turned 0.5 rad about x, its centre of mass
/// 0.1 m along its x axis: the sensor reads its weight and the weight's moment, in its frame.
#[test]
fn a_hanging_mass_weighs_on_its_sensor_in_the_child_frame() {
    for joints in ["multibody", "impulse"] {
        let mut s = sim(serde_json::json!({
            "world": "empty.toml", "precision": "f64",
            "robots": [{ "urdf": "test_mass.urdf", "base": "fixed", "joints": joints,
                "force_torque": ["sensor_joint"], "poses": [[2.0, 2.0, 1.0, 0.0, 0.0, 0.0]] }],
        }));
        s.advance_to(500_000_000, u64::MAX);
        let (name, force, torque) = s.force_torque(0)[0];
        let (sin, cos) = 0.5f64.sin_cos();
        let weight = [0.0, 9.81 * sin, 9.81 * cos];
        assert_eq!(name, "sensor_joint");
        assert!(close(force, weight, 1e-9), "{joints}: {force:?}");
        // About the joint: r × F with r = (0.1, 0, 0).
        let moment = [0.0, -0.1 * weight[2], 0.1 * weight[1]];
        assert!(close(torque, moment, 1e-9), "{joints}: {torque:?}");
    }
}

/// Without gravity, a 10 N push on a 4 kg cube carrying the 1 kg mass accelerates both at
/// 2 m/s²: the sensor reads the 2 N that accelerate the mass.
#[test]
fn a_pushed_body_accelerates_its_test_mass_through_the_sensor() {
    let mut s = sim(serde_json::json!({
        "world": "empty.toml", "precision": "f64", "gravity": 0.0,
        "robots": [{ "urdf": "pushed_mass.urdf", "force_torque": ["sensor_joint"],
            "poses": [[2.0, 2.0, 1.0, 0.0, 0.0, 0.0]] }],
    }));
    s.apply_wrench(0, &push_10_n()).unwrap();
    s.advance_to(200_000_000, u64::MAX);
    let (_, force, _) = s.force_torque(0)[0];
    assert!(close(force, [2.0, 0.0, 0.0], 1e-6), "{force:?}");
}

#[test]
fn a_sensor_on_a_moving_or_missing_joint_is_refused() {
    let params = |ft: &str| -> Params {
        caravan::parse_params(
            "physics",
            &serde_json::json!({
                "world": "empty.toml",
                "robots": [{ "urdf": "arm3.urdf", "base": "fixed", "force_torque": [ft],
                    "poses": [[2.0, 2.0, 0.0]] }],
            }),
        )
        .unwrap()
    };
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/robots");
    let e = load(&params("fore_joint"), &dir, 1_000_000)
        .err()
        .unwrap()
        .0;
    assert!(
        e.contains("'robots[0].force_torque[0]'") && e.contains("moves"),
        "{e}"
    );
    let e = load(&params("wrist"), &dir, 1_000_000).err().unwrap().0;
    assert!(e.contains("no joint named 'wrist'"), "{e}");
}

/// The same push on a soft sensor joint (rapier's softness 10 Hz, 0.3; rapier's rigid
/// default reads 2 N from the first step): the reading lags the load, rising without
/// overshoot to the 2 N.
#[test]
fn a_soft_sensor_joint_lags_the_load() {
    let mut s = sim(serde_json::json!({
        "world": "empty.toml", "precision": "f64", "gravity": 0.0,
        "robots": [{ "urdf": "pushed_mass.urdf", "force_torque": ["sensor_joint"],
            "force_torque_softness": { "natural_frequency_hz": 10.0, "damping_ratio": 0.3 },
            "poses": [[2.0, 2.0, 1.0, 0.0, 0.0, 0.0]] }],
    }));
    s.apply_wrench(0, &push_10_n()).unwrap();
    let mut readings = Vec::new();
    for k in 1..=300u64 {
        s.advance_to(k * 1_000_000, u64::MAX);
        readings.push(s.force_torque(0)[0].1[0]);
    }
    assert!(
        readings[9] < 1.0,
        "half the load is not reached in 10 ms: {}",
        readings[9]
    );
    assert!(
        readings.windows(2).all(|w| w[1] >= w[0] - 1e-9),
        "rises monotonically"
    );
    assert!(readings.iter().all(|r| *r <= 2.0 + 1e-6), "no overshoot");
    assert!(
        (readings[299] - 2.0).abs() < 2e-3,
        "settles: {}",
        readings[299]
    );
}

#[test]
fn a_bad_softness_is_refused_with_its_key() {
    let params = |mount: serde_json::Value, ft: &[&str]| {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/robots");
        let parsed = caravan::parse_params::<Params>(
            "physics",
            &serde_json::json!({
                "world": "empty.toml",
                "robots": [{ "urdf": "pushed_mass.urdf", "force_torque": ft,
                    "force_torque_softness": mount, "poses": [[2.0, 2.0, 0.0]] }],
            }),
        );
        match parsed {
            Err(e) => e.to_string(),
            Ok(p) => load(&p, &dir, 1_000_000).err().unwrap().0,
        }
    };
    let e = params(
        serde_json::json!({ "natural_frequency_hz": 0.0, "damping_ratio": 0.3 }),
        &["sensor_joint"],
    );
    assert!(
        e.contains("force_torque_softness.natural_frequency_hz"),
        "{e}"
    );
    let e = params(
        serde_json::json!({ "natural_frequency_hz": 10.0, "damping_ratio": -1.0 }),
        &["sensor_joint"],
    );
    assert!(e.contains("force_torque_softness.damping_ratio"), "{e}");
    let e = params(
        serde_json::json!({ "natural_frequency_hz": 10.0, "damping_ratio": 0.3 }),
        &[],
    );
    assert!(e.contains("'force_torque' names no joint"), "{e}");
    let e = params(
        serde_json::json!({ "natural_frequency_hz": 10.0 }),
        &["sensor_joint"],
    );
    assert!(e.contains("damping_ratio"), "{e}");
}
