//! Force–torque sensors on fixed joints against statics and F = m·a.

use caravan_physics::wrench::WrenchCommand;
use caravan_physics::{Params, Simulation, load};
use std::path::Path;

fn sim(params: serde_json::Value) -> Simulation {
    let params: Params = caravan::parse_params("physics", &params).unwrap();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/robots");
    load(&params, &dir, 1_000_000).unwrap()
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
    let push = WrenchCommand {
        link: "cube".into(),
        in_link_frame: true,
        point: [0.0, 0.0, 0.15 * 0.2],
        force: [10.0, 0.0, 0.0],
        torque: [0.0; 3],
        duration_s: 0.0,
    };
    s.apply_wrench(0, &push).unwrap();
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
