//! Contact identification from joint torques: the live scenario run briefly in lockstep from
//! its shipped launch file; its report scores every estimate against the push applied.

use caravan_tests::{launch_with_set, run_scenario, workspace_root};
use std::process::Command;

#[test]
fn a_live_run_tracks_each_push_within_the_monte_carlo_errors() {
    // Two pushes (1–3 s and 4–6 s), torque noise σ = 0.1 N·m.
    let run = run_scenario(
        "contact",
        "push.toml",
        &["--duration", "6.5s", "--set", "args.sigma=0.1"],
    );
    let c = &run.report["contact"];
    let live = &c["live"];
    assert_eq!(live["pushes"], 2, "{c}");
    assert!(live["scored"].as_u64().unwrap() > 2000, "{c}");
    assert_eq!(c["within_monte_carlo"], true, "{c}");
    // A 100 N push found to within a few newtons and millimetres, nearly always.
    assert!(live["force_error_n"]["mean"].as_f64().unwrap() < 2.0, "{c}");
    assert!(
        live["point_error_mm"]["mean"].as_f64().unwrap() < 5.0,
        "{c}"
    );
    assert!(live["no_solution_pct"].as_f64().unwrap() < 10.0, "{c}");
    assert_eq!(live["wrong_link_pct"], 0.0, "{c}");
    // At rest between pushes, (nearly) no contact is claimed.
    assert!(live["between_pushes"].as_u64().unwrap() > 100, "{c}");
    assert!(live["false_contact_pct"].as_f64().unwrap() < 10.0, "{c}");
    let svg = std::fs::read_to_string(run.dir.join(c["plot"].as_str().unwrap())).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("<circle"));
}

#[test]
fn without_noise_subtracting_the_arms_dynamics_leaves_under_a_thirtieth_of_the_static_error() {
    // One push (from 1 s, scored from 1.75 s: 350 estimates), no torque noise: the static
    // method reads the arm's leftover motion as part of the push; the dynamic one subtracts
    // M(q)·q̈ + C(q, q̇)·q̇ (over a full run it leaves a hundredth: docs/contact.md).
    let force_error = |dynamics: &str| {
        let run = run_scenario(
            "contact",
            "push.toml",
            &[
                "--duration",
                "2.1s",
                "--set",
                "args.sigma=0.0",
                "--set",
                &format!("args.dynamics={dynamics}"),
                // The Monte-Carlo beside the live run is not what this compares.
                "--set",
                "report.0.params.monte_carlo_trials=20",
            ],
        );
        let live = run.report["contact"]["live"].clone();
        assert_eq!(live["pushes"], 1, "{live}");
        assert_eq!(live["no_solution_pct"], 0.0, "{live}");
        live["force_error_n"]["mean"].as_f64().unwrap()
    };
    let (stat, dynamic) = (force_error("false"), force_error("true"));
    assert!(stat > 1e-3, "static {stat} N");
    assert!(
        dynamic < stat / 30.0,
        "dynamic {dynamic} N, static {stat} N"
    );
}

#[test]
fn without_noise_the_live_estimates_agree_with_an_independent_estimator() {
    // One push (from 1 s, scored from 1.75 s: 350 estimates), no torque noise. The script
    // python/examples/contact_independent/check.py re-estimates every scored instant by a
    // search over the links' contours (not the perception's analytical method) from the
    // recorded joint states, and scores both as the report does (docs/contact.md).
    let run = run_scenario(
        "contact",
        "push.toml",
        &[
            "--duration",
            "2.1s",
            "--set",
            "args.sigma=0.0",
            "--set",
            "report.0.params.monte_carlo_trials=20",
        ],
    );
    let root = workspace_root();
    let json = run.dir.join("independent.json");
    let out = Command::new(root.join("python/caravan-python"))
        .args(["--venv", "contact", "--requirements"])
        .arg("examples/contact_independent/requirements.txt")
        .arg(root.join("python/examples/contact_independent/check.py"))
        .arg(&run.dir)
        .arg("--json")
        .arg(&json)
        .env_remove("CARAVAN_PYTHON")
        .output()
        .expect("run python/caravan-python");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let stat = |side: &str, metric: &str, what: &str| s[side][metric][what].as_f64().unwrap();
    // The script scores the same estimates as the report, to the last digits.
    let live = &run.report["contact"]["live"];
    assert_eq!(s["pushes"], 1, "{s}");
    assert_eq!(s["scored"], live["scored"], "{s}");
    assert!(s["scored"].as_u64().unwrap() > 300, "{s}");
    for m in ["force_error_n", "point_error_mm", "direction_error_deg"] {
        let (ours, report) = (
            stat("live_vs_truth", m, "mean"),
            live[m]["mean"].as_f64().unwrap(),
        );
        assert!(
            (ours - report).abs() <= 1e-9 * report,
            "{m}: {ours} against {report}"
        );
    }
    // (a) The independent estimate against the push applied: the static model's only error is
    // the arm's leftover inertia in the torques, 0.016 N over a full run and 0.023 N (at
    // most 0.05 N) for this push, 0.08 mm; bounded at about twice that.
    assert_eq!(s["independent_no_point_pct"], 0.0, "{s}");
    assert_eq!(s["independent_wrong_link_pct"], 0.0, "{s}");
    assert!(
        stat("independent_vs_truth", "force_error_n", "mean") < 0.05,
        "{s}"
    );
    assert!(
        stat("independent_vs_truth", "force_error_n", "max") < 0.1,
        "{s}"
    );
    assert!(
        stat("independent_vs_truth", "point_error_mm", "mean") < 0.2,
        "{s}"
    );
    assert!(
        stat("independent_vs_truth", "direction_error_deg", "max") < 0.02,
        "{s}"
    );
    // (c) The live estimate against the independent one. Without noise both solve the same
    // three equations (the torques of the joints up to the pushed link) exactly, so they
    // agree far closer than either agrees with the push: 3e-10 N and 2e-9 mm at most
    // measured, from the search's last grid step (0.4 mm / 8⁹ ≈ 3e-12 m) and round-off. A
    // thousand times that still catches any change to the force or the point the estimator
    // reports (a force 5 % too large is 5 N off).
    assert!(
        stat("live_vs_independent", "force_error_n", "max") < 1e-6,
        "{s}"
    );
    assert!(
        stat("live_vs_independent", "point_error_mm", "max") < 1e-3,
        "{s}"
    );
    assert!(
        stat("live_vs_independent", "direction_error_deg", "max") < 1e-6,
        "{s}"
    );
}

/// Runs the shipped launch file briefly with `set`: the exit code and stderr.
fn launch_with(set: &str) -> (i32, String) {
    launch_with_set("contact/push.toml", "2s", set)
}

#[test]
fn bad_contact_input_is_named_and_fails_the_launch() {
    // Checked before anything starts: the report plugin's params and the URDF it reads.
    let (code, err) = launch_with("report.0.params.settle_s=-1.0");
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("settle_s"), "{err}");
    let (code, err) = launch_with("args.urdf=robots/none.urdf");
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("none.urdf"), "{err}");
    // A process's own params: named by the process, and the run fails.
    for (set, key) in [
        ("args.pose_deg=[10.0, 20.0]", "pose_deg"),
        ("process.driver.params.push.links=[0, 3]", "links"),
        ("process.depth.params.depth.beams=1", "beams"),
        (
            "process.contact-id.params.estimator.torque_sigmaa=1.0",
            "torque_sigmaa",
        ),
    ] {
        let (code, err) = launch_with(set);
        assert_ne!(code, 0, "{set}: {err}");
        assert!(err.contains(key), "{set}: {err}");
    }
}

/// Params out of their physical range (processes/contact/src/range.rs), refused before start.
#[path = "ranges/refused.rs"]
mod refused;
use refused::assert_refused_before_start;

#[test]
fn a_contact_sigma_of_1e308_is_refused_before_start() {
    assert_refused_before_start(
        "contact/push.toml",
        "args.sigma=1e308",
        "estimator.torque_sigma",
    );
}

#[test]
fn a_contact_report_sigma_of_1e308_is_refused_before_start() {
    // The report plugin alone: the perception keeps the shipped σ.
    assert_refused_before_start("contact/push.toml", "report.0.params.sigma=1e308", "sigma");
}

#[test]
fn an_arm_link_radius_of_1e308_is_refused_before_start() {
    assert_refused_before_start(
        "contact/push.toml",
        "process.contact-id.params.arm.link_radius=1e308",
        "arm.link_radius",
    );
}

#[test]
fn a_push_force_of_1e308_n_is_refused_before_start() {
    assert_refused_before_start(
        "contact/push.toml",
        "process.driver.params.push.force_n=[1e308, 1e308]",
        "push.force_n",
    );
}
