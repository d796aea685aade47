//! The engine at either precision: a free body pushed by a constant force accelerates at
//! F/m + g, to 1e-6 in f64.

use caravan_physics::wrench::WrenchCommand;
use caravan_physics::{Params, load};
use std::path::Path;

/// The 5 kg box at 3 m, pushed through its centre of mass by (10, 0, 20) N for 0.6 s under
/// gravity; its acceleration between 0.1 s and 0.6 s.
fn free_body_acceleration(precision: &str) -> [f64; 3] {
    let params: Params = caravan::parse_params(
        "physics",
        &serde_json::json!({
            "world": "empty.toml",
            "precision": precision,
            "robots": [{ "urdf": "box.urdf", "poses": [[2.0, 2.0, 3.0, 0.0, 0.0, 0.0]] }],
        }),
    )
    .unwrap();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/robots");
    let mut sim = load(&params, &dir, 1_000_000).unwrap();
    let push = WrenchCommand {
        link: "body".into(),
        in_link_frame: false,
        point: [2.0, 2.0, 3.0],
        force: [10.0, 0.0, 20.0],
        torque: [0.0; 3],
        duration_s: 0.0,
    };
    sim.apply_wrench(0, &push).unwrap();
    sim.advance_to(100_000_000, u64::MAX);
    let v1 = sim.twist(0).linear;
    sim.advance_to(600_000_000, u64::MAX);
    let v2 = sim.twist(0).linear;
    assert!(sim.base_height(0) > 1.0, "the box must not reach the floor");
    [
        (v2.x - v1.x) / 0.5,
        (v2.y - v1.y) / 0.5,
        (v2.z - v1.z) / 0.5,
    ]
}

/// Largest error relative to the expected acceleration's magnitude.
fn relative_error(a: [f64; 3]) -> f64 {
    let expected = [10.0 / 5.0, 0.0, 20.0 / 5.0 - 9.81];
    let norm = expected.iter().map(|e| e * e).sum::<f64>().sqrt();
    (0..3)
        .map(|k| (a[k] - expected[k]).abs() / norm)
        .fold(0.0, f64::max)
}

#[test]
fn a_free_body_accelerates_at_f_over_m_plus_g_to_1e_6_in_f64() {
    let f64_error = relative_error(free_body_acceleration("f64"));
    let f32_error = relative_error(free_body_acceleration("f32"));
    eprintln!("relative acceleration error: f64 {f64_error:.2e}, f32 {f32_error:.2e}");
    assert!(f64_error < 1e-6, "f64: {f64_error:e}");
    // f32 gets close, but not that close: the precision switch changes the engine.
    assert!(f32_error < 1e-3, "f32: {f32_error:e}");
}

/// A motor of constant torque spins a bar (I = 2.65 kg·m² about its axis, centre of mass
/// 0.278 m off it) at M/I, with either joint solver: rapier's default multibody damping is
/// switched off.
#[test]
fn a_constant_torque_spins_a_bar_at_m_over_i_with_either_solver() {
    use caravan_physics::actuator::Target;
    for joints in ["multibody", "impulse"] {
        let params: Params = caravan::parse_params(
            "physics",
            &serde_json::json!({
                "world": "empty.toml", "precision": "f64",
                "robots": [{ "urdf": "bar.urdf", "base": "fixed", "joints": joints,
                    "poses": [[2.0, 2.0, 1.0, 0.0, 0.0, 0.0]],
                    "actuators": [{ "type": "effort", "joints": ["bar_joint"] }] }],
            }),
        )
        .unwrap();
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/robots");
        let mut sim = load(&params, &dir, 1_000_000).unwrap();
        let motor = Target {
            effort: 5.0,
            ..Target::default()
        };
        sim.set_targets(0, &[motor]);
        let speed = |s: &caravan_physics::Simulation| s.joints(0).next().unwrap().2;
        sim.advance_to(100_000_000, u64::MAX);
        let w1 = speed(&sim);
        sim.advance_to(300_000_000, u64::MAX);
        let accel = (speed(&sim) - w1) / 0.2;
        let expected = 5.0 / 2.65;
        assert!(
            (accel - expected).abs() < 1e-5 * expected,
            "{joints}: {accel} rad/s², expected {expected}"
        );
    }
}
