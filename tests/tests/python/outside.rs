//! A scenario written outside the repository, as a user writes one from the docs: the files
//! of docs/scenarios.md ("A scenario of your own, anywhere, without Rust"), taken from the page
//! itself so that it cannot go stale. A pendulum in a URDF, a launch file that runs the
//! physics and a `caravan-script` timeline that pushes the bob once, and a report plugin in
//! Python that reads `record.mcap` with `caravan.recording` and scores the period. A sweep
//! over two lengths runs it; the periods are the pendulum's.

use caravan_tests::{TestGroup, python_env, workspace_bin, workspace_root};
use serde_json::Value;
use std::process::Command;

/// Standard gravity, which the launch file sets, m/s².
const G: f64 = 9.81;
/// The bob of the page's URDF: a 1 kg ball of radius 2 cm.
const MASS_KG: f64 = 1.0;
const RADIUS_M: f64 = 0.02;

/// The files the page shows: each code block after a `<!-- file: NAME -->` line.
fn files_of_the_page() -> Vec<(String, String)> {
    let page = std::fs::read_to_string(workspace_root().join("docs/scenarios.md")).unwrap();
    let mut files = Vec::new();
    let mut rest = page.as_str();
    while let Some(at) = rest.find("<!-- file: ") {
        let after = &rest[at + "<!-- file: ".len()..];
        let name = after[..after.find(" -->").unwrap()].to_string();
        let block = &after[after.find("```").unwrap()..];
        let body = &block[block.find('\n').unwrap() + 1..];
        let end = body.find("\n```").unwrap();
        files.push((name, body[..=end].to_string()));
        rest = &body[end..];
    }
    files
}

/// The period of a rigid pendulum of length `l` (the ball's own inertia included) swinging
/// with amplitude `a`, to fourth order in `a`.
fn period(l: f64, a: f64) -> f64 {
    let i_pivot = 0.4 * MASS_KG * RADIUS_M * RADIUS_M + MASS_KG * l * l;
    let t0 = 2.0 * std::f64::consts::PI * (i_pivot / (MASS_KG * G * l)).sqrt();
    t0 * (1.0 + a * a / 16.0 + 11.0 * a.powi(4) / 3072.0)
}

#[test]
fn a_scenario_written_outside_the_repository_in_python_is_swept() {
    python_env();
    let group = TestGroup::new("pendulum");
    let dir = std::env::temp_dir().join(format!("caravan-{}", group.name));
    std::fs::create_dir_all(&dir).unwrap();
    let files = files_of_the_page();
    let names: Vec<&str> = files.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "world.toml",
            "pendulum-0.5.urdf",
            "launch.toml",
            "report.py"
        ]
    );
    let caravan = workspace_root().display().to_string();
    for (name, text) in &files {
        let text = text
            .replace("/path/to/caravan", &caravan)
            .replace("name = \"pendulum\"", &format!("name = \"{}\"", group.name));
        std::fs::write(dir.join(name), &text).unwrap();
        if name == "pendulum-0.5.urdf" {
            // "the same with -1.0 for both -0.5s", as the page says.
            assert_eq!(text.matches("-0.5\"").count(), 2);
            std::fs::write(
                dir.join("pendulum-1.0.urdf"),
                text.replace("-0.5\"", "-1.0\""),
            )
            .unwrap();
        }
    }
    let out_dir = dir.join("sweep");
    let out = Command::new(workspace_bin("caravan"))
        .arg("sweep")
        .arg(dir.join("launch.toml"))
        .args(["--grid", "args.length=0.5,1.0", "--quiet", "--out"])
        .arg(&out_dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("summary.json")).unwrap())
            .unwrap();
    let cells = summary["cells"].as_array().unwrap();
    assert_eq!(cells.len(), 2);
    for cell in cells {
        // The grid's values keep their type: the lengths are numbers.
        let l = cell["values"]["args.length"].as_f64().unwrap();
        let m = &cell["metrics"];
        let measured = m["pendulum.period_s"]["mean"].as_f64().unwrap();
        let amplitude = m["pendulum.amplitude_rad"]["mean"].as_f64().unwrap();
        // Pushed, not released: a small swing (0.023 rad at 0.5 m, 0.008 rad at 1 m).
        assert!(amplitude > 0.004 && amplitude < 0.1, "{cell}");
        assert!(
            m["pendulum.swings"]["mean"].as_f64().unwrap() >= 2.0,
            "{cell}"
        );
        // The integrator's period error at ω·dt ≈ 0.004 is far below 1e-4, and the crossings
        // are interpolated between the 1 ms samples.
        let expected = period(l, amplitude);
        assert!(
            (measured - expected).abs() < 1e-3 * expected,
            "length {l} m: period {measured} s, expected {expected} s"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
