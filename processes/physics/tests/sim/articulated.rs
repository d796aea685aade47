//! Articulated robots against analytic mechanics: a pendulum's period, an arm's static joint
//! torques under gravity, and the torques a known wrench adds (Jᵀ·F).

use caravan_physics::actuator::Target;
use caravan_physics::wrench::WrenchCommand;
use caravan_physics::{Params, Simulation, load};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use std::path::{Path, PathBuf};

const G: f64 = 9.81;
/// 1 ms physics steps.
const DT_NS: u64 = 1_000_000;

fn robots_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/robots")
}

fn sim(robots: serde_json::Value) -> Simulation {
    let params: Params = caravan::parse_params(
        "physics",
        &serde_json::json!({ "world": "empty.toml", "robots": robots }),
    )
    .unwrap();
    load(&params, &robots_dir(), DT_NS).unwrap()
}

fn run(sim: &mut Simulation, seconds: f64) {
    let t = sim.time_ns() + (seconds * 1e9).round() as u64;
    sim.advance_to(t, u64::MAX);
}

#[test]
fn a_pendulum_swings_at_two_pi_root_l_over_g() {
    let mut s = sim(
        serde_json::json!([{ "urdf": "pendulum.urdf", "base": "fixed",
        "poses": [[2.0, 2.0, 0.0]] }]),
    );
    // A 20 ms, 1 N push starts a swing of about 0.02 rad.
    let push = WrenchCommand {
        link: "bob".into(),
        in_link_frame: true,
        point: [0.0, 0.0, -1.0],
        force: [1.0, 0.0, 0.0],
        torque: [0.0; 3],
        duration_s: 0.02,
    };
    s.apply_wrench(0, &push).unwrap();
    run(&mut s, 0.1);
    // Upward zero crossings of the joint angle, interpolated between steps.
    let mut crossings = Vec::new();
    let mut last = s.joints(0).next().unwrap().1;
    let mut amplitude: f64 = 0.0;
    while crossings.len() < 6 {
        s.step();
        let q = s.joints(0).next().unwrap().1;
        amplitude = amplitude.max(q.abs());
        if last < 0.0 && q >= 0.0 {
            let t = s.time_ns() as f64 * 1e-9 - (q / (q - last)) * DT_NS as f64 * 1e-9;
            crossings.push(t);
        }
        last = q;
    }
    let period = (crossings[5] - crossings[0]) / 5.0;
    let expected = 2.0 * std::f64::consts::PI * (1.0 / G).sqrt();
    assert!(
        amplitude > 0.005 && amplitude < 0.05,
        "small swing: {amplitude} rad"
    );
    let error = (period / expected - 1.0).abs();
    eprintln!(
        "pendulum: period {period:.6} s, 2π√(L/g) = {expected:.6} s, error {:.4} %",
        error * 100.0
    );
    assert!(
        error < 0.005,
        "period {period} s vs {expected} s ({:.3} %)",
        error * 100.0
    );
}

/// The arm's links: (name, centre of mass along the link's x, mass).
const ARM: [(&str, f64, f64); 3] = [
    ("upper", 0.25, 2.0),
    ("fore", 0.2, 1.0),
    ("hand", 0.15, 0.5),
];

fn arm() -> Simulation {
    sim(
        serde_json::json!([{ "urdf": "arm3.urdf", "base": "fixed", "poses": [[2.0, 2.0, 0.0]],
        // Damping ratios about 0.5 for each joint's load; kd·dt/I stays far below 1.
        "actuators": [
            { "type": "position", "joints": ["upper_joint"], "kp": 300.0, "ki": 300.0, "kd": 15.0 },
            { "type": "position", "joints": ["fore_joint"], "kp": 300.0, "ki": 300.0, "kd": 8.0 },
            { "type": "position", "joints": ["hand_joint"], "kp": 300.0, "ki": 300.0, "kd": 3.0 }],
        "link_states": true }]),
    )
}

/// World pose of every link of robot 0: (origin, rotation).
fn link_frames(s: &Simulation) -> Vec<(Vector3<f64>, UnitQuaternion<f64>)> {
    s.link_states(0)
        .iter()
        .map(|(p, _)| {
            let o = p.orientation;
            (
                Vector3::new(p.position.x, p.position.y, p.position.z),
                UnitQuaternion::from_quaternion(Quaternion::new(o.w, o.x, o.y, o.z)),
            )
        })
        .collect()
}

/// Torque about each joint (axis y of its child link) of force `f` acting at world point `p`
/// on link `on` (1-based link index along the chain) or beyond.
fn torques_of(
    frames: &[(Vector3<f64>, UnitQuaternion<f64>)],
    forces: &[(usize, Vector3<f64>, Vector3<f64>)],
) -> [f64; 3] {
    let mut tau = [0.0; 3];
    for (j, t) in tau.iter_mut().enumerate() {
        let (origin, rot) = frames[j + 1];
        let axis = rot * Vector3::y();
        for (on, p, f) in forces {
            if *on > j {
                *t += axis.dot(&(p - origin).cross(f));
            }
        }
    }
    tau
}

fn efforts(s: &Simulation) -> [f64; 3] {
    let e: Vec<f64> = s.joints(0).map(|(_, _, _, effort)| effort).collect();
    [e[0], e[1], e[2]]
}

fn hold(s: &mut Simulation, q: [f64; 3]) {
    let targets: Vec<Target> = q
        .iter()
        .map(|&position| Target {
            position,
            ..Target::default()
        })
        .collect();
    s.set_targets(0, &targets);
    run(s, 8.0);
}

fn gravity_forces(
    frames: &[(Vector3<f64>, UnitQuaternion<f64>)],
) -> Vec<(usize, Vector3<f64>, Vector3<f64>)> {
    ARM.iter()
        .enumerate()
        .map(|(k, (_, com, m))| {
            let (o, r) = frames[k + 1];
            (
                k + 1,
                o + r * Vector3::new(*com, 0.0, 0.0),
                Vector3::new(0.0, 0.0, -m * G),
            )
        })
        .collect()
}

fn assert_close(measured: [f64; 3], expected: [f64; 3], what: &str) {
    let worst = (0..3)
        .map(|j| ((measured[j] - expected[j]) / expected[j]).abs())
        .fold(0.0, f64::max);
    eprintln!(
        "{what}: {measured:?} vs {expected:?}, worst {:.4} %",
        worst * 100.0
    );
    for j in 0..3 {
        let rel = ((measured[j] - expected[j]) / expected[j]).abs();
        assert!(
            rel < 0.01,
            "{what}, joint {j}: {measured:?} vs {expected:?}"
        );
    }
}

#[test]
fn an_arm_holding_a_pose_carries_its_weight_in_its_joint_torques() {
    let mut s = arm();
    let q = [0.3, -0.5, 0.4];
    hold(&mut s, q);
    let measured: Vec<f64> = s.joints(0).map(|j| j.1).collect();
    for (m, t) in measured.iter().zip(q) {
        assert!(
            (m - t).abs() < 1e-3,
            "holds the pose: {measured:?} vs {q:?}"
        );
    }
    let frames = link_frames(&s);
    // The actuators balance gravity: τ = −Σ Jᵀ·m·g.
    let expected = torques_of(&frames, &gravity_forces(&frames)).map(|t| -t);
    assert_close(efforts(&s), expected, "static torques");
}

#[test]
fn a_servo_holds_zero_then_a_pose_and_its_effort_carries_the_weight() {
    // Impulse joints: rapier's motor; multibody joints: rapier's implicit joint spring.
    for model in ["impulse", "multibody"] {
        let mut s = sim(serde_json::json!([{ "urdf": "arm3.urdf", "base": "fixed",
            "poses": [[2.0, 2.0, 0.0]], "joints": model,
            "actuators": [{ "type": "servo", "joints": ["*"], "stiffness": 20000.0, "damping": 400.0 }],
            "link_states": true }]));
        // Never commanded: the URDF's zero, sagging by torque over stiffness only.
        run(&mut s, 2.0);
        let at_rest: Vec<f64> = s.joints(0).map(|j| j.1).collect();
        assert!(
            at_rest.iter().all(|q| q.abs() < 5e-3),
            "{model}: {at_rest:?}"
        );
        let q = [0.3, -0.5, 0.4];
        hold(&mut s, q);
        let measured: Vec<f64> = s.joints(0).map(|j| j.1).collect();
        let frames = link_frames(&s);
        let expected = torques_of(&frames, &gravity_forces(&frames)).map(|t| -t);
        for j in 0..3 {
            // A spring: it sits where its torque balances the load.
            let sag = expected[j] / 20000.0;
            assert!(
                (measured[j] + sag - q[j]).abs() < 1e-3,
                "{model}, joint {j}: {measured:?} vs {q:?}, sag {sag}"
            );
        }
        assert_close(
            efforts(&s),
            expected,
            &format!("a servo's static torques ({model})"),
        );
    }
}

#[test]
fn a_kinematic_arm_moves_at_its_speed_limit_and_holds_a_pose_without_sag() {
    let mut s = sim(serde_json::json!([{ "urdf": "arm3.urdf", "base": "fixed",
        "poses": [[2.0, 2.0, 0.0]], "joints": "multibody",
        "actuators": [{ "type": "kinematic", "joints": ["*"] }] }]));
    // Never commanded: it stands still at zero under gravity.
    run(&mut s, 0.5);
    assert!(s.joints(0).all(|j| j.1.abs() < 1e-6), "stands still");
    // 2 rad at the URDF's 5 rad/s, clamped to its 2.5 rad limit: 0.4 s, then held.
    let targets = [2.0, -3.0, 0.4].map(|position| Target {
        position,
        ..Target::default()
    });
    s.set_targets(0, &targets);
    run(&mut s, 0.2);
    let halfway = s.joints(0).next().unwrap().1;
    assert!((halfway - 1.0).abs() < 0.01, "5 rad/s for 0.2 s: {halfway}");
    run(&mut s, 2.0);
    for ((name, q, speed, effort), want) in s.joints(0).zip([2.0, -2.5, 0.4]) {
        assert!((q - want).abs() < 1e-4, "{name}: {q} vs {want}");
        // Still, but for the single-precision poses' rounding.
        assert!(
            speed.abs() < 1e-2 && effort == 0.0,
            "{name}: {speed}, {effort}"
        );
    }
    // A speed target runs the joint to its limit and no further.
    let targets = [1.0, 0.0, -1.0].map(|velocity| Target {
        position: f64::INFINITY,
        velocity,
        ..Target::default()
    });
    s.set_targets(0, &targets);
    run(&mut s, 4.0);
    for ((name, q, _, _), want) in s.joints(0).zip([2.5, -2.5, -2.5]) {
        assert!((q - want).abs() < 1e-3, "{name}: {q} vs its limit {want}");
    }
}

#[test]
fn a_wrench_on_the_third_link_adds_j_transpose_f() {
    let mut s = arm();
    let q = [0.2, -0.3, 0.5];
    hold(&mut s, q);
    let before = efforts(&s);
    let point = [0.2, 0.0, 0.0];
    let force = Vector3::new(6.0, 0.0, -15.0);
    s.apply_wrench(
        0,
        &WrenchCommand {
            link: "hand".into(),
            in_link_frame: false,
            point: {
                let (o, r) = link_frames(&s)[3];
                (o + r * Vector3::from(point)).into()
            },
            force: force.into(),
            torque: [0.0; 3],
            duration_s: 0.0,
        },
    )
    .unwrap();
    run(&mut s, 8.0);
    let after = efforts(&s);
    let frames = link_frames(&s);
    let (o, r) = frames[3];
    let at = o + r * Vector3::from(point);
    let expected = torques_of(&frames, &[(3, at, force)]).map(|t| -t);
    let change = [0, 1, 2].map(|j| after[j] - before[j]);
    assert_close(change, expected, "torque change");
}

#[test]
fn a_kinematic_base_flies_at_its_commanded_velocity() {
    let mut s = sim(
        serde_json::json!([{ "urdf": "box.urdf", "base": "kinematic",
        "cmd_vel_frame": "body", "poses": [[1.0, 1.0, 1.5, 0.0, 0.0, std::f64::consts::FRAC_PI_2]] }]),
    );
    let cmd = caravan_schemas::Twist::planar(0.5, 0.0);
    s.set_cmd_vel(0, &cmd);
    run(&mut s, 2.0);
    // Forward in the body frame is +y in the world at yaw 90°; no gravity on a kinematic body.
    let p = s.pose(0);
    // rapier moves a velocity-based kinematic body from the step after the command: one
    // step's travel (0.5 mm) short.
    let step = 0.5 * DT_NS as f64 * 1e-9;
    assert!(
        (p.x - 1.0).abs() < 1e-4 && (p.y - 2.0 + step).abs() < 1e-4,
        "{p:?}"
    );
    assert!((s.base_height(0) - 1.5).abs() < 1e-6);
}

#[test]
fn bad_robot_kinds_are_refused_with_the_key() {
    let error = |robots: serde_json::Value| {
        let params: Params = caravan::parse_params(
            "physics",
            &serde_json::json!({ "world": "empty.toml", "robots": robots }),
        )
        .unwrap();
        match load(&params, &robots_dir(), DT_NS) {
            Ok(_) => panic!("accepted {robots}"),
            Err(e) => e.to_string(),
        }
    };
    let e = error(serde_json::json!([{ "urdf": "arm3.urdf", "base": "fixed",
        "poses": [[2.0, 2.0, 0.0]], "actuators": [{ "type": "effort", "joints": ["elbow"] }] }]));
    assert!(
        e.contains("robots[0].actuators[0].joints") && e.contains("no joint named 'elbow'"),
        "{e}"
    );
    let e = error(
        serde_json::json!([{ "urdf": "arm3.urdf", "base": "floating",
        "poses": [[2.0, 2.0, 0.0]] }]),
    );
    assert!(
        e.contains("link 'post'") && e.contains("floating base") && e.contains("arm3.urdf:5"),
        "{e}"
    );
    let e = error(
        serde_json::json!([{ "urdf": "pendulum.urdf", "base": "fixed",
        "poses": [[2.0, 2.0, 0.0]], "drive": "diff" }]),
    );
    assert!(e.contains("robots[0].drive"), "{e}");
    let e = error(serde_json::json!([{ "urdf": "missing.urdf" }]));
    assert!(
        e.contains("robots[0].urdf") && e.contains("missing.urdf"),
        "{e}"
    );
}

#[test]
fn an_actuator_on_a_fixed_joint_is_refused() {
    let params: Params = caravan::parse_params(
        "physics",
        &serde_json::json!({ "world": "empty.toml", "robots": [{ "urdf": "fixed_actuated.urdf",
            "base": "fixed", "poses": [[2.0, 2.0, 0.0]],
            "actuators": [{ "type": "velocity", "joints": ["weld"] }] }] }),
    )
    .unwrap();
    let e = load(&params, &robots_dir(), DT_NS)
        .err()
        .expect("refused")
        .to_string();
    assert!(e.contains("joint 'weld'") && e.contains("is fixed"), "{e}");
}
