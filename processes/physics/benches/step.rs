//! Physics step times: the convoy (5 robots, DC motors, 2 ms steps), a three-link arm under
//! position control (1 ms) and a 36-wheel tracked robot (2 ms), each in f32 and f64; and,
//! printed first, what f32 and f64 give on the IMU's static case (an IMU on the arm's hand,
//! read every physics step while position control holds the arm still).
//!
//! Run with `cargo bench -p caravan-physics --bench step`.

use caravan_physics::actuator::Target;
use caravan_physics::{Params, Simulation, load};
use caravan_sensor::attach::link_state;
use caravan_sensor::imu::{ImuNoise, Mount, VirtualImu};
use criterion::{BatchSize, Criterion};
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Duration;

fn crate_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

fn sim(params: serde_json::Value, dir: &Path, dt_ns: u64) -> Simulation {
    let params: Params = caravan::parse_params("physics", &params).unwrap();
    load(&params, dir, dt_ns).unwrap()
}

/// The convoy's five robots in the lab, driving forward.
fn convoy(precision: &str) -> Simulation {
    let dir = crate_dir().join("../../launch/convoy");
    let mut s = sim(
        serde_json::json!({ "world": "worlds/lab.toml", "urdf": "robots/convoy_bot.urdf",
            "count": 5, "precision": precision }),
        &dir,
        2_000_000,
    );
    let go = caravan_schemas::WheelSetpoint {
        left_rad_s: 4.0,
        right_rad_s: 4.5,
    };
    for i in 0..s.robot_count() {
        s.set_setpoint(i, &go);
    }
    s
}

/// The three-link arm held at (0.3, −0.3, 0) rad by per-joint position loops.
fn arm(precision: &str) -> Simulation {
    let dir = crate_dir().join("tests/robots");
    let position = |joint: &str, kp: f64, ki: f64, kd: f64| serde_json::json!({ "type": "position", "joints": [joint], "kp": kp, "ki": ki, "kd": kd });
    let mut s = sim(
        serde_json::json!({
            "world": "empty.toml", "precision": precision,
            "robots": [{ "urdf": "arm3.urdf", "base": "fixed", "poses": [[1.0, 1.0, 0.0]],
                "actuators": [position("upper_joint", 400.0, 1000.0, 20.0),
                    position("fore_joint", 200.0, 500.0, 10.0),
                    position("hand_joint", 20.0, 50.0, 0.5)] }],
        }),
        &dir,
        1_000_000,
    );
    let targets = [0.3, -0.3, 0.0].map(|q| Target {
        position: q,
        ..Target::default()
    });
    s.set_targets(0, &targets);
    s
}

/// A tracked robot: a 1 × 0.5 × 0.2 m, 20 kg hull on 2 × 18 road wheels (r = 0.05 m), every
/// wheel speed-controlled, written as URDF into a temporary directory.
fn tracked(precision: &str) -> Simulation {
    let dir = std::env::temp_dir().join(format!("caravan-bench-tracked-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut urdf = String::from(
        r#"<robot name="tracked"><link name="base_link"><inertial><mass value="20"/>
<inertia ixx="0.48" iyy="1.73" izz="2.08" ixy="0" ixz="0" iyz="0"/></inertial>
<collision><origin xyz="0 0 0.1"/><geometry><box size="1.0 0.5 0.2"/></geometry></collision></link>
"#,
    );
    for side in ["left", "right"] {
        let y = if side == "left" { 0.3 } else { -0.3 };
        for k in 0..18 {
            let x = -0.45 + k as f64 * 0.9 / 17.0;
            urdf += &format!(
                r#"<link name="{side}_{k}"><inertial><mass value="0.2"/>
<inertia ixx="0.00015" iyy="0.00025" izz="0.00015" ixy="0" ixz="0" iyz="0"/></inertial>
<collision><origin rpy="1.5708 0 0"/><geometry><cylinder radius="0.05" length="0.04"/></geometry></collision></link>
<joint name="{side}_{k}_joint" type="continuous"><parent link="base_link"/><child link="{side}_{k}"/>
<origin xyz="{x} {y} 0"/><axis xyz="0 1 0"/><limit effort="5" velocity="20"/></joint>
"#
            );
        }
    }
    urdf += "</robot>\n";
    std::fs::write(dir.join("tracked.urdf"), urdf).unwrap();
    std::fs::copy(
        crate_dir().join("tests/robots/empty.toml"),
        dir.join("empty.toml"),
    )
    .unwrap();
    let mut s = sim(
        serde_json::json!({
            "world": "empty.toml", "precision": precision,
            "robots": [{ "urdf": "tracked.urdf", "poses": [[2.0, 2.0, 0.0]],
                "actuators": [{ "type": "velocity", "joints": ["*"], "kp": 2.0 }] }],
        }),
        &dir,
        2_000_000,
    );
    let targets: Vec<Target> = (0..36)
        .map(|k| Target {
            velocity: if k < 18 { 4.0 } else { 5.0 },
            ..Target::default()
        })
        .collect();
    s.set_targets(0, &targets);
    s
}

/// Worst deviation of an IMU on the arm's hand from |f| = g and ω = 0 over one second of
/// readings at every 1 ms physics step, after twenty seconds of settling (the position loops'
/// integral terms take a few seconds to bring the arm to rest).
fn imu_static(precision: &str) -> (f64, f64) {
    let mut s = arm(precision);
    s.advance_to(20_000_000_000, u64::MAX);
    let mount = Mount {
        offset: nalgebra::Vector3::new(0.3, 0.0, 0.0),
    };
    let mut imu = VirtualImu::new(mount, ImuNoise::OFF, 0);
    let mut states = caravan_schemas::placement_new::<caravan_schemas::LinkStates>();
    let (mut accel, mut gyro) = (0.0f64, 0.0f64);
    for _ in 0..1000 {
        s.step();
        caravan_physics::messages::link_states(&s, 0, &mut states);
        let (body, ..) = link_state(s.time_ns(), &states, "hand").unwrap();
        if let Some(r) = imu.update(&body) {
            accel = accel.max((r.linear_acceleration.norm() - 9.81).abs());
            gyro = gyro.max(r.angular_velocity.norm());
        }
    }
    (accel, gyro)
}

/// Builds a simulation at a precision ("f32" or "f64").
type Builder = fn(&str) -> Simulation;

fn step_benches(c: &mut Criterion) {
    let cases: [(&str, Builder); 3] = [
        ("convoy (5 robots)", convoy),
        ("arm (3 joints)", arm),
        ("tracked (36 wheels)", tracked),
    ];
    let mut group = c.benchmark_group("physics step");
    group
        .sample_size(30)
        .measurement_time(Duration::from_secs(4));
    for (name, make) in cases {
        for precision in ["f32", "f64"] {
            // Measured after one simulated second, once the robots are under way.
            let mut s = make(precision);
            s.advance_to(1_000_000_000, u64::MAX);
            group.bench_function(format!("{name} {precision}"), |b| {
                b.iter_batched_ref(|| (), |_| s.step(), BatchSize::SmallInput)
            });
            black_box(s.time_ns());
        }
    }
    group.finish();
}

fn main() {
    for precision in ["f32", "f64"] {
        let (accel, gyro) = imu_static(precision);
        println!(
            "IMU static case, {precision}: worst | |f| − g | = {accel:.2e} m/s², worst |ω| = {gyro:.2e} rad/s"
        );
    }
    let mut c = Criterion::default().configure_from_args();
    step_benches(&mut c);
    c.final_summary();
}
