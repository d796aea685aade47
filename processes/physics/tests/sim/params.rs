//! The params' checks that need no file: keys, forms, counts and values, each refusal naming
//! its key (moved from `params.rs`).

use caravan_physics::Params;
use caravan_physics::firmware::FirmwareParams;
use caravan_physics::motor::MotorParams;
use serde_json::json;

fn parse(v: serde_json::Value) -> Result<Params, String> {
    let p: Params = caravan::parse_params("physics", &v).map_err(|e| e.to_string())?;
    p.validate()?;
    Ok(p)
}

/// `v` with `world` added.
fn in_world(mut v: serde_json::Value) -> serde_json::Value {
    v["world"] = json!("w.toml");
    v
}

#[test]
fn the_world_and_the_robots_are_required() {
    let e = parse(json!({"urdf": "r.urdf", "count": 5})).unwrap_err();
    assert!(e.starts_with("key 'world': missing"), "{e}");
    let e = parse(json!({"world": "w.toml"})).unwrap_err();
    assert!(
        e.starts_with("key 'robots': missing") && e.contains("urdf"),
        "{e}"
    );
    let e = parse(json!({"world": "w.toml", "urdf": "r.urdf"})).unwrap_err();
    assert!(e.starts_with("key 'count': missing"), "{e}");
    for one_kind_key in [json!({"count": 2}), json!({"motor": {"k_t": 0.02}})] {
        let e = parse(in_world(one_kind_key)).unwrap_err();
        assert!(e.starts_with("key 'urdf': missing"), "{e}");
    }
    let p = parse(json!({"world": "w.toml", "urdf": "r.urdf", "count": 5})).unwrap();
    assert_eq!(p.robot_specs().unwrap()[0].count, 5);
    assert!(p.poses.is_empty(), "the world's start poses");
}

#[test]
fn the_one_kind_form_is_a_robots_entry_on_dc_motors() {
    let top = parse(in_world(
        json!({"urdf": "r.urdf", "count": 2, "lifted": true,
        "motor": {"gear_ratio": 50.0}, "pid": {"kp": 1.0}}),
    ))
    .unwrap();
    let entry = parse(in_world(json!({"robots": [{"urdf": "r.urdf", "count": 2,
        "lifted": true, "joints": "impulse", "drive": "diff", "joint_states": false,
        "actuators": [{"type": "dc_motor", "joints": ["*"],
                       "motor": {"gear_ratio": 50.0}, "pid": {"kp": 1.0}}]}]})))
    .unwrap();
    assert_eq!(top.robot_specs(), entry.robot_specs());
    let spec = &top.robot_specs().unwrap()[0];
    let caravan_physics::spec::ActuatorSpec::DcMotor { motor, pid, .. } = &spec.actuators[0] else {
        panic!("{spec:?}")
    };
    // The keys left out keep the dc_motor's defaults: the convoy robot's measured motor.
    assert_eq!(motor.supply_v, MotorParams::default().supply_v);
    assert_eq!(pid.ki, FirmwareParams::default().ki);
}

#[test]
fn pose_count_mismatch_names_the_key() {
    let e = parse(in_world(json!({"urdf": "r.urdf", "count": 2,
        "poses": [[1.0, 1.0, 0.0]]})))
    .unwrap_err();
    assert!(e.contains("'poses'") && e.contains("count = 2"), "{e}");
}

#[test]
fn robots_of_several_kinds() {
    let p = parse(in_world(json!({"robots": [
        {"urdf": "arm.urdf", "base": "fixed", "actuators": [
            {"type": "position", "joints": ["*"], "kp": 50.0}]},
        {"urdf": "drone.urdf", "base": "kinematic", "count": 2,
         "poses": [[1.0, 1.0, 2.0, 0.0, 0.0, 0.0], [2.0, 1.0, 0.0]]}]})))
    .unwrap();
    let specs = p.robot_specs().unwrap();
    assert_eq!(specs.len(), 2);
    assert_eq!(specs[1].count, 2);
    assert_eq!(
        specs[0].joint_model(),
        caravan_physics::spec::JointModel::Multibody
    );
    assert_eq!(
        specs[1].joint_model(),
        caravan_physics::spec::JointModel::Impulse
    );
}

#[test]
fn an_empty_robot_list_is_an_error() {
    let e = parse(in_world(json!({"robots": []}))).unwrap_err();
    assert!(e.contains("robots") && e.contains("an empty list"), "{e}");
}

#[test]
fn robot_kind_errors_name_the_key() {
    let robots = |r: serde_json::Value| parse(in_world(json!({ "robots": [r] })));
    let e = robots(json!({"urdf": "a.urdf", "poses": [[1.0, 2.0]]})).unwrap_err();
    assert!(e.contains("key 'robots[0].poses[0]'"), "{e}");
    let e = robots(json!({"urdf": "a.urdf",
        "actuators": [{"type": "position", "joints": ["j"], "kp": -1.0}]}))
    .unwrap_err();
    assert!(
        e.contains("'robots[0].actuators[0]'") && e.contains("kp"),
        "{e}"
    );
    let e = robots(json!({"urdf": "a.urdf",
        "actuators": [{"type": "servo", "joints": ["j"], "stiffness": 0.0}]}))
    .unwrap_err();
    assert!(
        e.contains("'robots[0].actuators[0]'") && e.contains("stiffness"),
        "{e}"
    );
    let e = robots(json!({"urdf": "a.urdf",
        "actuators": [{"type": "dc_motor", "joints": ["j"], "motor": {"k_t": 0.0}}]}))
    .unwrap_err();
    assert!(
        e.contains("'robots[0].actuators[0]'") && e.contains("motor.k_t"),
        "{e}"
    );
    let e = robots(json!({"urdf": "a.urdf",
        "actuators": [{"type": "torque", "joints": ["j"]}]}))
    .unwrap_err();
    assert!(e.contains("torque"), "{e}");
    let e = parse(in_world(
        json!({"count": 2, "robots": [{"urdf": "a.urdf"}]}),
    ))
    .unwrap_err();
    assert!(e.contains("not both"), "{e}");
}

#[test]
fn unknown_keys_are_rejected() {
    let e = parse(json!({"motor": {"resistance": 3.0}})).unwrap_err();
    assert!(e.contains("motor.resistance"), "{e}");
}
