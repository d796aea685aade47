//! Initial joint states on every joint solver and the actuators that hold them: the arm
//! starts where `initial_positions` puts it and stays there under a servo or kinematic joints;
//! a kinematic joint keeps its initial speed; link poses agree between the solvers.

use caravan_physics::{Params, Simulation, load};
use std::path::Path;

fn sim(robot: serde_json::Value) -> Simulation {
    let params = serde_json::json!({ "world": "empty.toml", "robots": [robot] });
    let params: Params = caravan::parse_params("physics", &params).unwrap();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/robots");
    load(&params, &dir, 2_000_000).unwrap()
}

fn arm(joints: &str, actuator: &str) -> Simulation {
    sim(
        serde_json::json!({ "urdf": "arm3.urdf", "base": "fixed", "poses": [[2.0, 2.0, 0.0]],
        "joints": joints, "link_states": true,
        "actuators": [{ "type": actuator, "joints": ["*"] }],
        "initial_positions": { "upper_joint": 0.6, "fore_joint": -0.9, "hand_joint": 0.3 } }),
    )
}

fn positions(s: &Simulation) -> Vec<f64> {
    s.joints(0).map(|j| j.1).collect()
}

#[test]
fn an_arm_starts_at_its_initial_positions_and_its_actuators_hold_them() {
    let want = [0.6, -0.9, 0.3];
    let mut hands = Vec::new();
    for (joints, actuator, hold) in [
        ("multibody", "servo", 0.02),
        ("impulse", "servo", 0.02),
        ("multibody", "kinematic", 1e-5),
    ] {
        let mut s = arm(joints, actuator);
        for (q, w) in positions(&s).iter().zip(want) {
            assert!(
                (q - w).abs() < 1e-6,
                "{joints} {actuator}: starts at {q}, not {w}"
            );
        }
        hands.push(s.link_states(0)[3].0.position);
        s.advance_to(1_000_000_000, u64::MAX);
        for (q, w) in positions(&s).iter().zip(want) {
            assert!(
                (q - w).abs() < hold,
                "{joints} {actuator}: {q} after 1 s, not {w}"
            );
        }
    }
    // The bodies stand where the joints say, on either solver.
    for h in &hands[1..] {
        let d = (h.x - hands[0].x).abs() + (h.z - hands[0].z).abs();
        assert!(d < 1e-5, "{h:?} vs {:?}", hands[0]);
    }
}

#[test]
fn a_kinematic_joint_keeps_its_initial_speed() {
    let mut s = sim(serde_json::json!({ "urdf": "arm3.urdf", "base": "fixed",
        "poses": [[2.0, 2.0, 0.0]], "joints": "multibody",
        "actuators": [{ "type": "kinematic", "joints": ["*"] }],
        "initial_velocities": { "upper_joint": 1.5 } }));
    assert_eq!(s.joints(0).next().unwrap().2, 1.5);
    s.advance_to(400_000_000, u64::MAX);
    let (_, q, v, _) = s.joints(0).next().unwrap();
    assert!((q - 0.6).abs() < 1e-4 && (v - 1.5).abs() < 1e-4, "{q}, {v}");
}
