//! `link_states` against kinematics computed here from the URDF alone, over random chains of
//! revolute and prismatic joints on a fixed base: each link's pose is the forward kinematics
//! of the joint positions read, its twist the derivative of those kinematics along the joint
//! speeds read (a central difference of 1e-6 in the joint space, exact to round-off), and
//! both agree with central differences of the poses over two physics steps. Driven chains
//! move their kinematic joints at constant speeds; passive ones swing and slide under gravity.

use caravan_physics::{Params, Simulation, load};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use proptest::prelude::*;
use std::path::Path;

const DT_NS: u64 = 1_000_000;
const DT: f64 = 1e-3;

/// One joint of a random chain, in its parent's frame.
#[derive(Debug, Clone)]
struct RandomJoint {
    prismatic: bool,
    xyz: [f64; 3],
    rpy: [f64; 3],
    axis: [f64; 3],
    /// The child link's centre of mass, in its frame.
    com: [f64; 3],
    /// Its speed when driven, rad/s or m/s.
    speed: f64,
}

fn joint() -> impl Strategy<Value = RandomJoint> {
    let v = |r: f64| prop::array::uniform3(-r..r);
    (any::<bool>(), v(0.4), v(3.1), v(1.0), v(0.3), -2.0..2.0f64)
        .prop_filter("an axis", |j| Vector3::from(j.3).norm() > 0.2)
        .prop_map(|(prismatic, xyz, rpy, axis, com, speed)| RandomJoint {
            prismatic,
            xyz,
            rpy,
            axis,
            com,
            speed,
        })
}

/// The chain's URDF: `base`, then `link1` … `linkN`.
fn urdf(joints: &[RandomJoint]) -> String {
    let f = |v: &[f64; 3]| format!("{} {} {}", v[0], v[1], v[2]);
    let mut s = String::from("<robot name=\"chain\">\n<link name=\"link0\"/>\n");
    for (k, j) in joints.iter().enumerate() {
        s += &format!(
            "<link name=\"link{}\"><inertial><origin xyz=\"{}\"/><mass value=\"1\"/>\
             <inertia ixx=\"0.01\" iyy=\"0.01\" izz=\"0.01\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/>\
             </inertial></link>\n",
            k + 1,
            f(&j.com)
        );
        s += &format!(
            "<joint name=\"j{k}\" type=\"{}\"><parent link=\"link{k}\"/><child link=\"link{}\"/>\
             <origin xyz=\"{}\" rpy=\"{}\"/><axis xyz=\"{}\"/>\
             <limit lower=\"-100\" upper=\"100\" effort=\"1000\" velocity=\"10\"/></joint>\n",
            if j.prismatic {
                "prismatic"
            } else {
                "continuous"
            },
            k + 1,
            f(&j.xyz),
            f(&j.rpy),
            f(&j.axis)
        );
    }
    s + "</robot>\n"
}

fn simulation(dir: &Path, joints: &[RandomJoint], driven: bool) -> Simulation {
    std::fs::write(dir.join("chain.urdf"), urdf(joints)).unwrap();
    std::fs::write(
        dir.join("empty.toml"),
        "[world]\nname = \"empty\"\nsize = [4.0, 4.0]\n",
    )
    .unwrap();
    let names: Vec<String> = (0..joints.len()).map(|k| format!("j{k}")).collect();
    let actuators = if driven {
        serde_json::json!([{ "type": "kinematic", "joints": names }])
    } else {
        serde_json::json!([])
    };
    let params: Params = caravan::parse_params(
        "physics",
        &serde_json::json!({ "world": "empty.toml", "precision": "f64", "substeps": 1,
            "robots": [{ "urdf": "chain.urdf", "base": "fixed", "link_states": true,
                "poses": [[2.0, 2.0, 1.5, 0.3, -0.2, 0.7]], "actuators": actuators }] }),
    )
    .unwrap();
    let mut sim = load(&params, dir, DT_NS).unwrap();
    if driven {
        let targets: Vec<_> = joints
            .iter()
            .map(|j| caravan_physics::actuator::Target {
                velocity: j.speed,
                ..Default::default()
            })
            .collect();
        sim.set_targets(0, &targets);
    }
    sim
}

/// The world poses of every link at joint positions `q`, from the URDF's numbers alone.
fn forward(base: &Isometry3<f64>, joints: &[RandomJoint], q: &[f64]) -> Vec<Isometry3<f64>> {
    let mut poses = vec![*base];
    for (j, q) in joints.iter().zip(q) {
        let [r, p, y] = j.rpy;
        let origin = Isometry3::from_parts(
            Translation3::from(Vector3::from(j.xyz)),
            UnitQuaternion::from_euler_angles(r, p, y),
        );
        let axis = Vector3::from(j.axis).normalize();
        let motion = if j.prismatic {
            Isometry3::translation(axis.x * q, axis.y * q, axis.z * q)
        } else {
            Isometry3::rotation(axis * *q)
        };
        poses.push(poses.last().unwrap() * origin * motion);
    }
    poses
}

fn isometry(p: &caravan_schemas::Pose3D) -> Isometry3<f64> {
    let (t, q) = (&p.position, &p.orientation);
    Isometry3::from_parts(
        Translation3::new(t.x, t.y, t.z),
        UnitQuaternion::from_quaternion(Quaternion::new(q.w, q.x, q.y, q.z)),
    )
}

type Twist = (Vector3<f64>, Vector3<f64>);

fn twist(t: &caravan_schemas::Twist) -> Twist {
    let v = |m: &caravan_schemas::Vector3| Vector3::new(m.x, m.y, m.z);
    (v(&t.linear), v(&t.angular))
}

/// The rotation vector of `q`, by atan2: precise for the tiny rotations of a difference,
/// where an acos of the scalar part loses half the digits.
fn rotation_vector(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    let q = if q.w < 0.0 {
        -q.into_inner()
    } else {
        q.into_inner()
    };
    let n = q.imag().norm();
    if n == 0.0 {
        return Vector3::zeros();
    }
    q.imag() * (2.0 * n.atan2(q.w) / n)
}

/// The twist taking pose `a` to pose `b` in `dt`: the origin's mean velocity and the
/// rotation vector of b·a⁻¹ over dt.
fn difference(a: &Isometry3<f64>, b: &Isometry3<f64>, dt: f64) -> Twist {
    (
        (b.translation.vector - a.translation.vector) / dt,
        rotation_vector(&(b.rotation * a.rotation.inverse())) / dt,
    )
}

fn close(a: &Twist, b: &Twist, tol: f64) -> bool {
    (a.0 - b.0).norm() <= tol && (a.1 - b.1).norm() <= tol
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    #[test]
    fn link_twists_are_the_derivatives_of_the_link_poses(
        joints in prop::collection::vec(joint(), 1..=4),
        driven in any::<bool>(),
    ) {
        let dir = std::env::temp_dir().join(format!(
            "caravan-link-twists-{}-{}",
            std::process::id(),
            std::thread::current().name().unwrap_or("main").replace("::", "-")
        ));
        std::fs::create_dir_all(&dir).unwrap();
        let mut sim = simulation(&dir, &joints, driven);
        let base = isometry(&sim.link_states(0)[0].0);
        let mut history: Vec<Vec<(Isometry3<f64>, Twist)>> = Vec::new();
        for step in 0..300 {
            sim.step();
            let states: Vec<(Isometry3<f64>, Twist)> = sim
                .link_states(0)
                .iter()
                .map(|(p, t)| (isometry(p), twist(t)))
                .collect();
            // Against the URDF's kinematics at the joint positions and speeds read.
            let (q, qd): (Vec<f64>, Vec<f64>) = sim.joints(0).map(|(_, q, v, _)| (q, v)).unzip();
            let h = 1e-6;
            let at = |s: f64| {
                let q: Vec<f64> = q.iter().zip(&qd).map(|(q, v)| q + s * v).collect();
                forward(&base, &joints, &q)
            };
            let (now, before, after) = (at(0.0), at(-h), at(h));
            for (k, (pose, tw)) in states.iter().enumerate() {
                let p = pose.translation.vector - now[k].translation.vector;
                let r = rotation_vector(&(pose.rotation * now[k].rotation.inverse())).norm();
                prop_assert!(p.norm() < 1e-9 && r < 1e-9, "link {k} at step {step}: pose off by {p:?}, {r} rad");
                let analytic = difference(&before[k], &after[k], 2.0 * h);
                prop_assert!(close(tw, &analytic, 1e-7), "link {k} at step {step}: {tw:?} vs {analytic:?}");
            }
            history.push(states);
        }
        // Against the poses themselves: a central difference over the steps either side. At
        // constant joint speeds it is second-order accurate (a twist one step stale, as rapier
        // leaves a multibody link body's, is off by ω²·r·dt, over 1e-3 here). A passive
        // chain's joints accelerate, and rapier's semi-implicit step moves the poses by the
        // speed after each step, so the difference is the mean of the twists at k and k + 1:
        // off by about a quarter of the twist's change from k − 1 to k + 1. Besides, the
        // generalized speeds rapier's solver leaves in a passive chain ripple from step to
        // step by some 1e-5 of their size about the smooth motion its poses follow (seen
        // here: 0.304708, 0.304721, 0.304712 rad/s at three steps whose pose differences give
        // 0.3047173 and 0.3047179), hence the 1e-4 floor.
        for k in 1..history.len() - 1 {
            for (link, (_, tw)) in history[k].iter().enumerate() {
                let d = difference(&history[k - 1][link].0, &history[k + 1][link].0, 2.0 * DT);
                let (a, b) = (history[k - 1][link].1, history[k + 1][link].1);
                let change = (b.0 - a.0).norm().max((b.1 - a.1).norm());
                let tol = if driven { 1e-4 } else { 1e-4 + 0.5 * change };
                prop_assert!(close(tw, &d, tol), "link {link} at step {k}: {tw:?} vs {d:?}");
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}

#[test]
fn a_free_multibody_root_reports_its_velocity_after_the_step() {
    // A body with a wheel on a passive joint (so that rapier keeps it as a multibody with a
    // free root), no colliders, falling from rest: after step k every link moves at −g·k·dt,
    // the speed the step ended with (a velocity one step stale reads −g·(k − 1)·dt).
    let dir = std::env::temp_dir().join(format!("caravan-free-root-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let joints = [RandomJoint {
        prismatic: false,
        xyz: [0.1, 0.0, 0.0],
        rpy: [0.0; 3],
        axis: [0.0, 1.0, 0.0],
        com: [0.0; 3],
        speed: 0.0,
    }];
    std::fs::write(
        dir.join("chain.urdf"),
        urdf(&joints).replace(
            "<link name=\"link0\"/>",
            "<link name=\"link0\"><inertial><origin xyz=\"0.05 0.02 0\"/><mass value=\"2\"/>\
         <inertia ixx=\"0.01\" iyy=\"0.01\" izz=\"0.01\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/>\
         </inertial></link>",
        ),
    )
    .unwrap();
    std::fs::write(
        dir.join("empty.toml"),
        "[world]\nname = \"empty\"\nsize = [4.0, 4.0]\n",
    )
    .unwrap();
    let params: Params = caravan::parse_params(
        "physics",
        &serde_json::json!({ "world": "empty.toml", "precision": "f64", "substeps": 1,
            "robots": [{ "urdf": "chain.urdf", "base": "floating", "joints": "multibody",
                "link_states": true, "ground_truth": true, "poses": [[2.0, 2.0, 0.3]] }] }),
    )
    .unwrap();
    let mut sim = load(&params, &dir, DT_NS).unwrap();
    let g = 9.81;
    for k in 1..=50 {
        sim.step();
        let expected = -g * k as f64 * DT;
        for (link, (_, t)) in sim.link_states(0).iter().enumerate() {
            let (v, w) = twist(t);
            assert!(
                (v.z - expected).abs() < 1e-9,
                "link {link}, step {k}: {v:?} vs {expected}"
            );
            assert!(
                v.x.abs() < 1e-9 && v.y.abs() < 1e-9 && w.norm() < 1e-9,
                "{v:?} {w:?}"
            );
        }
        let (_, truth) = sim.ground_truth(0);
        assert!(
            (truth.linear.z - expected).abs() < 1e-9,
            "ground truth, step {k}"
        );
        assert!(
            (sim.twist(0).linear.z - expected).abs() < 1e-9,
            "twist_true, step {k}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
