//! Physical ranges of the scenario's params (the arm, the depth sensor, the pushes, the
//! estimator, the report): every number finite, of its sign, and within what the experiment
//! has, so that a typo (`1e308`) is refused before the group starts (each process's `setup`
//! and the report's `new` run under the launcher's check) with a message naming the key, in
//! the style of the other processes (`key 'push.force_n': must be between …, got 1e308`),
//! instead of a run that overflows or a report that never ends. Each bound's constant says
//! why it is what it is.

pub use caravan::range::{above, between, shown};

/// The latest time a key may name, s: a day. The shipped run lasts 20 s; a day of simulated
/// time at the arm's 1 kHz physics is 86.4 million steps, hours of wall time even in a
/// release build, so a later time is a typo.
pub const MAX_TIME_S: f64 = 86_400.0;

/// The thinnest link surface (the stadium's radius), m: below a millimetre the surface is
/// finer than the depth sensor's default range noise (5 mm) and its contour's entry points
/// are round-off.
pub const MIN_LINK_RADIUS_M: f64 = 1e-3;

/// The thickest, m: a link is 2r wide, and Caravan caps a part of a robot description at
/// 100 m across (`caravan_world::limits::MAX_PART_SIZE_M`).
pub const MAX_LINK_RADIUS_M: f64 = caravan_world::limits::MAX_PART_SIZE_M / 2.0;

/// The hand's radius, m: from a fingertip's millimetre to a metre (a whole body leaning on
/// the arm); the reference's hand is 4 cm.
pub const HAND_RADIUS_M: [f64; 2] = [1e-3, 1.0];

/// The hardest push, N: a person pushes with at most about a thousand newtons (a strong
/// adult's whole-body push, more than the 210 N the collaborative-robot limits of
/// ISO/TS 15066 allow on a hand). The arm's joints bound it further in the working pose:
/// [`crate::scenario::PushParams::spec`].
pub const MAX_PUSH_N: f64 = 1000.0;

/// The largest friction coefficient: dry surfaces stay below about 2 (soft rubber); 5 leaves
/// room, and its cone (±79°) already takes nearly every direction.
pub const MAX_MU: f64 = 5.0;

/// The noisiest torque sensors, and the highest unloaded floor, N·m: ten times the
/// reference's noisiest level (2 N·m). There 3σ = 60 N·m is already most of the torque a
/// 100 N push makes at the arm's reach; beyond it the thresholds hide every push.
pub const MAX_TORQUE_NOISE_N_M: f64 = 20.0;

/// The depth sensor's longest range, m: a sparse time-of-flight sensor or small lidar reads
/// metres to tens of metres; 100 m is past any the scenario stands for.
pub const MAX_DEPTH_RANGE_M: f64 = 100.0;

/// The depth sensor's range noise and self-filter margin, m, at most a metre: more than any
/// of the arm's links is long, a return then no longer tells the arm from the hand.
pub const MAX_DEPTH_NOISE_M: f64 = 1.0;

/// Where the depth sensor may sit, m, within ±10 km of the arm: Caravan's largest world
/// (`caravan_world::limits::MAX_WORLD_EXTENT_M`).
pub const MAX_COORDINATE_M: f64 = caravan_world::limits::MAX_WORLD_EXTENT_M;

/// Monte-Carlo trials of the report, at most 10⁵: 50 times its default, a few minutes in a
/// debug build, within the report's default time limit (10 min).
pub const MAX_REPORT_TRIALS: usize = 100_000;

const _: () = assert!(MIN_LINK_RADIUS_M < MAX_LINK_RADIUS_M);
const _: () = assert!(HAND_RADIUS_M[0] < HAND_RADIUS_M[1]);

#[cfg(test)]
mod tests {
    use super::*;

    use crate::arm_urdf::{ArmModel, from_description, urdf};
    use crate::monte_carlo::reference_arm;
    use crate::scenario::{ArmParams, DepthParams, EstimatorParams, PushParams, pose_rad};
    use serde_json::{Value, json};

    /// The shipped arm, read back from its generated URDF.
    fn model() -> ArmModel {
        let text = urdf(&reference_arm());
        let d = caravan_world::description::parse(&text, "arm.urdf", std::path::Path::new("."))
            .unwrap();
        from_description(&d, 0.05).unwrap()
    }

    /// The shipped working pose (launch/contact/push.toml), rad.
    fn pose(m: &ArmModel) -> Vec<f64> {
        pose_rad(m, &[20.0, 70.0, -50.0, 60.0, 30.0]).unwrap()
    }

    /// The driver's pushes with `push` over the shipped ones, at its 100 Hz.
    fn push(push: Value) -> Result<(), String> {
        let mut p = json!({ "links": [3, 4], "hand_radius_m": 0.04 });
        p.as_object_mut()
            .unwrap()
            .extend(push.as_object().unwrap().clone());
        let m = model();
        let p: PushParams = serde_json::from_value(p).unwrap();
        p.spec(&m, &pose(&m), 0.01).map(|_| ())
    }

    #[test]
    fn the_shipped_params_are_in_range() {
        push(json!({})).unwrap();
        DepthParams::default().scanner().unwrap();
        let e: EstimatorParams = serde_json::from_value(json!({ "torque_sigma": 2.0 })).unwrap();
        e.settings().unwrap();
    }

    #[test]
    fn a_push_force_of_1e308_n_is_refused() {
        let e = push(json!({ "force_n": [1e308, 1e308] })).unwrap_err();
        assert_eq!(
            e,
            "key 'push.force_n': [min, max] must hold 0 < min ≤ max ≤ 1000 N (a person's \
             hardest push), got [1e308, 1e308]"
        );
        for bad in [
            json!([0.0, 10.0]),
            json!([20.0, 10.0]),
            json!([1.0, 1001.0]),
        ] {
            let e = push(json!({ "force_n": bad })).unwrap_err();
            assert!(e.starts_with("key 'push.force_n'"), "{bad}: {e}");
        }
    }

    #[test]
    fn a_push_harder_than_the_joints_hold_in_the_pose_is_refused() {
        // The joints hold 400 N·m; links 3 and 4 reach up to about 1.4 m from joint 1.
        push(json!({ "force_n": [90.0, 250.0] })).unwrap();
        let e = push(json!({ "force_n": [90.0, 900.0] })).unwrap_err();
        assert!(
            e.starts_with("key 'push.force_n': at most")
                && e.contains("joint 'joint1'")
                && e.contains("400 N·m"),
            "{e}"
        );
    }

    #[test]
    fn push_times_and_the_hand_out_of_range_are_named() {
        for (bad, key) in [
            (json!({ "push_s": 1e308 }), "push.push_s"),
            (json!({ "push_s": 0.005 }), "push.push_s"),
            (json!({ "gap_s": 1e-300 }), "push.gap_s"),
            (json!({ "start_s": -1.0 }), "push.start_s"),
            (json!({ "mu": 1e308 }), "push.mu"),
            (json!({ "hand_radius_m": 1e308 }), "push.hand_radius_m"),
        ] {
            let e = push(bad.clone()).unwrap_err();
            assert!(e.starts_with(&format!("key '{key}'")), "{bad}: {e}");
        }
    }

    #[test]
    fn a_contact_sigma_of_1e308_is_refused() {
        let e: EstimatorParams = serde_json::from_value(json!({ "torque_sigma": 1e308 })).unwrap();
        assert_eq!(
            e.settings().unwrap_err(),
            "key 'estimator.torque_sigma': must be between 0 and 20 N·m, got 1e308"
        );
        for (bad, key) in [
            (json!({ "torque_floor": 1e308 }), "estimator.torque_floor"),
            (json!({ "mu": -0.1 }), "estimator.mu"),
        ] {
            let e: EstimatorParams = serde_json::from_value(bad).unwrap();
            assert!(
                e.settings()
                    .unwrap_err()
                    .starts_with(&format!("key '{key}'"))
            );
        }
    }

    #[test]
    fn an_arm_link_radius_of_1e308_is_refused_before_its_urdf_is_read() {
        let arm: ArmParams =
            serde_json::from_value(json!({ "urdf": "none.urdf", "link_radius": 1e308 })).unwrap();
        let e = arm.load(std::path::Path::new("none.urdf")).unwrap_err();
        assert_eq!(
            e,
            "key 'arm.link_radius': must be between 0.001 and 50 m, got 1e308"
        );
    }

    #[test]
    fn depth_sensor_keys_out_of_range_are_named() {
        for (bad, key) in [
            (json!({ "origin": [1e308, 0.0] }), "depth.origin[0]"),
            (json!({ "first_angle_deg": 1e308 }), "depth.first_angle_deg"),
            (json!({ "fov_deg": 0.0 }), "depth.fov_deg"),
            (json!({ "beams": 100000 }), "depth.beams"),
            (json!({ "max_range_m": 1e308 }), "depth.max_range_m"),
            (json!({ "range_sigma_m": 1e308 }), "depth.range_sigma_m"),
            (json!({ "self_filter_m": -1.0 }), "depth.self_filter_m"),
        ] {
            let d: DepthParams = serde_json::from_value(bad.clone()).unwrap();
            let e = d.scanner().unwrap_err();
            assert!(e.starts_with(&format!("key '{key}'")), "{bad}: {e}");
        }
    }

    #[test]
    fn a_pose_beyond_its_joints_limits_is_refused() {
        let m = model();
        let e = pose_rad(&m, &[20.0, 70.0, -50.0, 60.0, 1e308]).unwrap_err();
        assert!(
            e.starts_with("key 'pose_deg': joint 'joint5' must be between -180.00° and 180.00°"),
            "{e}"
        );
    }

    #[test]
    fn the_bounds_fit_the_robot_description_caps() {
        assert_eq!(2.0 * MAX_LINK_RADIUS_M, 100.0);
    }
}
