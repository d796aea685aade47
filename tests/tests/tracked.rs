//! The tracked robot scenario: each running-gear variant driven briefly in lockstep from the
//! shipped launch files, under a unique group name; the `tracked` report section must show
//! it moving as commanded, level on flat ground, and over a 10 cm step.

use caravan_tests::{launch_with_set, run_scenario, workspace_bin};
use serde_json::Value;

#[path = "tracked/params.rs"]
mod params;

/// Runs `launch/tracked/<file>` with `extra` arguments; returns the `tracked` section.
fn run(file: &str, extra: &[&str]) -> Value {
    run_scenario("tracked", file, extra).report["tracked"].clone()
}

#[test]
fn every_variant_drives_straight_and_level_on_flat_ground() {
    // Every variant on rims (the default), and v4 on rapier's kinematic joints too.
    let cases = [
        ("v1", "rim"),
        ("v2", "rim"),
        ("v3", "rim"),
        ("v4", "rim"),
        ("v4", "kinematic"),
    ];
    for (variant, wheels) in cases {
        let t = run(
            "flat.toml",
            &[
                "--set",
                &format!("args.variant={variant}"),
                "--set",
                &format!("args.wheels={wheels}"),
                "--set",
                "args.duration=3s",
            ],
        );
        // 0.3 m/s asked from 0.5 s, reached at 0.2 m/s² 1.5 s later: 0.525 m by 3 s, as the
        // wheels turn at the drive's speed whatever the load.
        let moved = t["max_x_m"].as_f64().unwrap() - 1.0;
        assert!(
            moved > 0.49 && moved < 0.54,
            "{variant} on {wheels}: moved {moved} m: {t}"
        );
        assert!(t["max_tilt_deg"].as_f64().unwrap() < 3.0, "{variant}: {t}");
        assert_eq!(t["outcome"], "stuck", "{variant}: the goal is 5 m away");
    }
}

/// The reference's mobility figures: top speed and braking distance (the drive decelerates
/// at its 0.2 m/s² limit: 0.4 m from 0.4 m/s).
#[test]
fn v4_reaches_its_top_speed_and_brakes_at_the_drives_limit() {
    let t = run(
        "flat.toml",
        &[
            "--set",
            "args.speed=0.4",
            "--set",
            "process.driver.params.stop_s=3.0",
            "--set",
            "args.duration=6s",
        ],
    );
    let top = t["top_speed_m_s"].as_f64().unwrap();
    assert!(top > 0.38 && top < 0.45, "{top}: {t}");
    assert_eq!(t["stop_s"].as_f64(), Some(3.0), "{t}");
    let braking = t["braking_distance_m"].as_f64().unwrap();
    assert!((braking - 0.4).abs() < 0.04, "{braking}: {t}");
}

/// The driver steers back to its line: set off 0.3 m to the left of the line y = 1.5 m, the
/// robot ends on it, which only steering can bring about.
#[test]
fn the_driver_steers_back_to_its_line() {
    let t = run(
        "flat.toml",
        &[
            "--set",
            "args.pose=[1.0, 1.8, 0.0]",
            "--set",
            "process.driver.params.keep_line.line=[0.0, 1.5, 0.0]",
            "--set",
            "args.duration=9s",
        ],
    );
    let track = t["track"].as_array().unwrap();
    let last = track.last().unwrap().as_array().unwrap();
    let (x, y) = (last[1].as_f64().unwrap(), last[2].as_f64().unwrap());
    assert!((y - 1.5).abs() < 0.05, "ended at y = {y}: {t}");
    assert!(x > 2.5, "x = {x}: {t}");
}

#[test]
fn v4_climbs_a_10_cm_step() {
    let t = run("step.toml", &["--set", "args.step=10"]);
    assert_eq!(t["outcome"], "passed", "{t}");
    assert!(t["max_climb_m"].as_f64().unwrap() > 0.09, "{t}");
}

/// The reference's highest step: the driver works the flippers (up to reach the edge, down
/// to carry the front over it) and v4 climbs 20 cm, but not 30 cm.
#[test]
fn v4_climbs_20_cm_with_its_flippers_and_not_30() {
    let t = run("step.toml", &["--set", "args.step=20"]);
    assert_eq!(t["outcome"], "passed", "{t}");
    assert!(t["max_climb_m"].as_f64().unwrap() > 0.19, "{t}");
    // The nose rose well past the push threshold: the flippers had to work.
    assert!(t["max_tilt_deg"].as_f64().unwrap() > 30.0, "{t}");
    // And it ends level on top, the flippers raised again (base 0.093 m above the step).
    let last = t["track"].as_array().unwrap().last().unwrap().clone();
    let (z, tilt) = (last[3].as_f64().unwrap(), last[4].as_f64().unwrap());
    assert!(
        (z - 0.293).abs() < 0.02 && tilt < 5.0,
        "ends at z {z}, tilt {tilt}: {t}"
    );
    let t = run("step.toml", &["--set", "args.step=30"]);
    assert_ne!(t["outcome"], "passed", "{t}");
    assert!(t["max_x_m"].as_f64().unwrap() < 2.2, "{t}");
}

#[test]
fn bad_driver_params_fail_the_launch_naming_the_key() {
    for (set, key) in [
        (
            "process.driver.params.keep_line.lookahead_m=0.0",
            "keep_line.lookahead_m",
        ),
        (
            "process.driver.params.keep_line.line=[1.0, 1.5]",
            "keep_line",
        ),
        (
            "process.driver.params.keep_line.straight_above_tilt_deg=90.0",
            "keep_line.straight_above_tilt_deg",
        ),
        (
            "process.driver.params.climb.push_deg=-120.0",
            "climb.push_deg",
        ),
        (
            "process.driver.params.climb.crest_deg=5.0",
            "climb.crest_deg",
        ),
        ("process.driver.params.climb.speed=1.0", "speed"),
        (
            "process.drive.params.flipper_angle_rad=\"up\"",
            "flipper_angle_rad",
        ),
    ] {
        let (code, err) = launch_with_set("tracked/step.toml", "2s", set);
        assert_ne!(code, 0, "{set}: {err}");
        assert!(err.contains(key) && err.contains("driv"), "{set}: {err}");
    }
}

#[test]
fn an_unknown_wheel_model_fails_the_launch_naming_the_key() {
    let (code, err) = launch_with_set("tracked/step.toml", "2s", "args.wheels=tank");
    assert_ne!(code, 0, "{err}");
    assert!(
        err.contains("actuators[0].type") && err.contains("tank") && err.contains("rim"),
        "{err}"
    );
}

/// Writes a terrain with the real generator: 2 m of ground, a 1 m field of 5 cm holes
/// among ground blocks, 1 m of run-out.
fn holes_terrain(dir: &std::path::Path) -> std::path::PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let spec = dir.join("holes.toml");
    std::fs::write(
        &spec,
        "[terrain]\nseed = 4\nfield = [1.0, 3.0]\napproach = 2.0\nrun_out = 1.0\n\
         [[primitive]]\ntype = \"random\"\nmin = 0.05\nmax = 0.1\n",
    )
    .unwrap();
    generated_world(&spec, 4, &dir.join("holes-world.toml"))
}

/// Runs the generator on `spec` with `seed` into `world`.
fn generated_world(
    spec: &std::path::Path,
    seed: u64,
    world: &std::path::Path,
) -> std::path::PathBuf {
    let out = std::process::Command::new(workspace_bin("caravan-tracked-terrain"))
        .arg(spec)
        .arg("--seed")
        .arg(seed.to_string())
        .arg("--out")
        .arg(world)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    world.to_path_buf()
}

/// Drives `variant` across `world` with `terrain.toml` and `extra` arguments.
fn drive_on(world: &std::path::Path, variant: &str, extra: &[&str]) -> Value {
    let (variant, world) = (
        format!("args.variant={variant}"),
        format!("args.world={}", world.display()),
    );
    let mut args = vec!["--set", variant.as_str(), "--set", world.as_str()];
    args.extend_from_slice(extra);
    run("terrain.toml", &args)
}

/// The shipped hills spec at `seed`, written in a directory of its own: (directory, world).
fn hills_world(seed: u64) -> (std::path::PathBuf, std::path::PathBuf) {
    let dir = std::env::temp_dir().join(format!(
        "caravan-tracked-hills{seed}-{}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let spec = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../launch/tracked/terrains/hills.toml");
    let world = generated_world(&spec, seed, &dir.join(format!("hills-{seed}.toml")));
    (dir, world)
}

#[test]
fn gear_wheels_climb_a_hill_where_round_wheels_stop_at_its_first_stair() {
    // The shipped hills spec at seed 21: the lane meets a hill's 10 cm stairs at the field's
    // start, one track before the other (docs/tracked-passability.md). v4 climbs over it
    // since the chassis' nose is bevelled (with the square nose it stuck there); v1 stops.
    let (dir, world) = hills_world(21);
    let extra = ["--set", "args.contacts=true"];
    let drive = |variant: &str| drive_on(&world, variant, &extra);
    let gear = drive("v4");
    assert_eq!(gear["outcome"], "passed", "{gear}");
    assert!(gear["max_climb_m"].as_f64().unwrap() > 0.09, "{gear}");
    // Driving out over the run-out, it rests on its wheels alone.
    assert_eq!(gear["chassis_share"].as_f64(), Some(0.0), "{gear}");
    let round = drive("v1");
    assert_eq!(round["outcome"], "stuck", "{round}");
    assert!(round["max_climb_m"].as_f64().unwrap() < 0.05, "{round}");
    assert!(round["max_x_m"].as_f64().unwrap() < 2.2, "{round}");
    // Its wheels turn against the stair's face; its chassis touches nothing.
    assert!(round["chassis_share"].as_f64().unwrap() < 0.05, "{round}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_gear_robot_stuck_on_a_hill_rests_on_its_chassis() {
    // The shipped hills spec at seed 6, v4 with its flippers at 15° (the passability
    // protocol's angle): it stops on a hill's flank high-centred, its belly on a stair's edge
    // bearing two fifths of the contact force (docs/tracked-passability.md, where the gears stop).
    let (dir, world) = hills_world(6);
    let extra = [
        "--set",
        "args.contacts=true",
        "--set",
        "process.drive.params.flipper_angle_rad=0.26",
    ];
    let t = drive_on(&world, "v4", &extra);
    assert_eq!(t["outcome"], "stuck", "{t}");
    assert_eq!(t["high_centred"], true, "{t}");
    assert!(t["chassis_share"].as_f64().unwrap() > 0.4, "{t}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn every_variant_makes_a_short_crossing_of_a_generated_terrain() {
    let dir = std::env::temp_dir().join(format!("caravan-tracked-holes-{}", std::process::id()));
    let world = holes_terrain(&dir);
    for variant in ["v1", "v2", "v3", "v4"] {
        let extra = ["--set", "args.goal_x=3.5", "--set", "args.duration=11s"];
        let t = drive_on(&world, variant, &extra);
        let track = t["track"].as_array().unwrap();
        // It starts on the ground blocks (0.1 m above the floor), not on the floor.
        let z0 = track[0][3].as_f64().unwrap();
        assert!(z0 > 0.17 && z0 < 0.21, "{variant}: starts at z = {z0}: {t}");
        // It reaches the field (x = 2 m; the base is 0.4 m behind the flippers' tips).
        assert!(t["max_x_m"].as_f64().unwrap() > 1.7, "{variant}: {t}");
        let outcome = t["outcome"].as_str().unwrap();
        let passed = t["max_x_m"].as_f64().unwrap() >= 3.5;
        assert_eq!(outcome == "passed", passed, "{variant}: {t}");
        // The big wheels roll over 10 cm holes; the small ones drop in (docs/tracked.md).
        if variant == "v3" || variant == "v4" {
            assert_eq!(outcome, "passed", "{variant}: {t}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_terrain_specs_and_arguments_exit_2_naming_file_and_key() {
    let dir = std::env::temp_dir().join(format!("caravan-tracked-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let terrain = |spec: Option<&str>, args: &[&str]| {
        let path = dir.join("bad.toml");
        if let Some(text) = spec {
            std::fs::write(&path, text).unwrap();
        }
        let out = std::process::Command::new(workspace_bin("caravan-tracked-terrain"))
            .arg(&path)
            .args(args)
            .output()
            .unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let out = ["--out", "/nonexistent-dir/w.toml"];
    let head = "[terrain]\nfield = [3.0, 3.0]\n";
    for (spec, needle) in [
        (
            format!(
                "{head}[[primitive]]\ntype = \"peak\"\ncenter = [1.0, 1.0]\nheight = 0.25\nradius = 1.0\n"
            ),
            "key 'primitive[0].height': 0.25 is not a step",
        ),
        (
            format!("{head}[[primitive]]\ntype = \"wall\"\n"),
            "unknown variant `wall`",
        ),
        ("[terrain]\nfield = [3.0]\n".to_string(), "line 2"),
        (
            "[terrain]\nfield = [2.95, 3.0]\n".to_string(),
            "terrain.field[0]",
        ),
    ] {
        let (code, err) = terrain(Some(&spec), &out);
        assert_eq!(code, Some(2), "{spec}: {err}");
        assert!(
            err.contains("bad.toml") && err.contains(needle),
            "{spec}: {err}"
        );
    }
    // A good spec, an unwritable output: exit 2 naming the output.
    let good = format!("{head}[[primitive]]\ntype = \"random\"\nmin = 0.05\nmax = 0.1\n");
    let (code, err) = terrain(Some(&good), &out);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("/nonexistent-dir/w.toml"), "{err}");
    // Bad arguments.
    let (code, err) = terrain(None, &["--seeds", "5..2", "--out-dir", "x"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("range 5..2 is empty"), "{err}");
    let (code, err) = terrain(
        None,
        &["--seeds", "0..18446744073709551615", "--out-dir", "x"],
    );
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("more than the 100000 one command takes"),
        "{err}"
    );
    let (code, _) = terrain(None, &[]);
    assert_eq!(code, Some(2));
    // The passability table of a directory without a sweep summary.
    let out = std::process::Command::new(workspace_bin("caravan-tracked-passability"))
        .arg(&dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("summary.json"));
    // Without its argument it says how to call it.
    let out = std::process::Command::new(workspace_bin("caravan-tracked-passability"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("<SWEEP_DIR>"));
    let _ = std::fs::remove_dir_all(&dir);
}
