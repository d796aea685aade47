//! The `imu` report section: every IMU reading of `robot/0/imu` scored against its phase's
//! ideal value (see [`crate::scenario`]), per phase and axis, against the reference's targets
//! of 1e-6 m/s² and 1e-6 rad/s.
//!
//! JSON: `{scenario, readings, phases: [PhaseErrors], accel_max_err_m_s2,
//! gyro_max_err_rad_s, accel_target_m_s2, gyro_target_rad_s, within_target}`.

use crate::arm::{Arm, ArmGeometry};
use crate::phase_errors::{PhaseErrors, Reading, score};
use crate::scenario::Scenario;
use crate::spin_up::{self, Bar};
use caravan_report::{Inputs, ReportPlugin, Run, Section};
use std::fmt::Write;

/// The reference's accuracy targets.
pub const ACCEL_TARGET_M_S2: f64 = 1e-6;
pub const GYRO_TARGET_RAD_S: f64 = 1e-6;

/// The plot of the readings, in the run directory.
pub const PLOT_FILE: &str = "imu.svg";

/// The plot of the two accelerometer designs' vertical readings, when the run has both.
pub const FORCE_PLOT_FILE: &str = "imu-force-sensor.svg";

/// The Allan-deviation plot of the `allan` scenario.
pub const ALLAN_PLOT_FILE: &str = "allan.svg";

/// The test mass of the rejected force-sensor accelerometer, kg (the scenarios' URDFs).
pub const TEST_MASS_KG: f64 = 1.0;

/// The force–torque topic of the scenarios' one robot.
pub const FORCE_TOPIC: &str = "robot/0/force_torque";

/// The IMU topic of the scenarios' one robot.
pub const IMU_TOPIC: &str = "robot/0/imu";

pub struct ImuReport {
    scenario: Scenario,
    /// The lifted cube's mass, kg (0 for other scenarios).
    mass_kg: f64,
    /// The spin-up's bar and motor.
    bar: Option<Bar>,
    /// The arm's keys and geometry.
    arm: Option<(Arm, ArmGeometry)>,
}

impl ReportPlugin for ImuReport {
    type Params = Scenario;

    fn new(scenario: Scenario, inputs: &Inputs) -> Result<Self, String> {
        scenario.validate()?;
        let load = |urdf: &str| {
            caravan_world::description::load_description(&inputs.path(urdf))
                .map_err(|e| format!("key 'urdf': robot description {e}"))
        };
        let mut arm = None;
        let (mass_kg, bar) = match &scenario {
            Scenario::Lift { urdf, .. } => {
                let mass_kg = load(urdf)?.mass();
                scenario.validate_forces(mass_kg)?;
                (mass_kg, None)
            }
            Scenario::SpinUp { urdf, joint, .. } => {
                (0.0, Some(Bar::from_description(&load(urdf)?, joint)?))
            }
            Scenario::Arm(_) => {
                arm = Arm::load(&scenario, load)?;
                (0.0, None)
            }
            _ => (0.0, None),
        };
        Ok(Self {
            scenario,
            mass_kg,
            bar,
            arm,
        })
    }

    fn sections(&self, run: &Run) -> anyhow::Result<Vec<Section>> {
        let v3 = |v: &serde_json::Value| ["x", "y", "z"].map(|k| v[k].as_f64().unwrap_or(f64::NAN));
        let readings: Vec<Reading> = run
            .messages()?
            .iter()
            .filter(|m| m.topic == IMU_TOPIC)
            .map(|m| Reading {
                t_s: m.stamp_ns() as f64 * 1e-9,
                accel: v3(&m.json["linear_acceleration"]),
                gyro: v3(&m.json["angular_velocity"]),
            })
            .collect();
        if readings.is_empty() {
            anyhow::bail!("no IMU readings on {IMU_TOPIC} in the recording");
        }
        let title = format!("IMU readings: {}", self.scenario.name());
        crate::plot::readings_svg(&run.dir.join(PLOT_FILE), &title, &readings)?;
        if let Some(bar) = &self.bar {
            return Ok(vec![spin_up_section(bar, &readings)?]);
        }
        if let Scenario::Allan { imu_errors } = &self.scenario {
            return Ok(vec![allan_section(imu_errors, &readings, &run.dir)?]);
        }
        let windows = match &self.arm {
            Some((arm, g)) => arm.phases(g),
            None => self.scenario.phases(self.mass_kg),
        };
        let phases: Vec<PhaseErrors> = windows.iter().map(|p| score(p, &readings)).collect();
        // The design the reference study rejected, where the run records it: a test mass on
        // a force sensor, a = F/m. Physics stamps a force with the end of its step; the
        // sensor publishes the IMU reading of that step at its next step, so the reading
        // of the same interval is the first one stamped after the force.
        let same_interval = |t: f64| {
            let k = readings.partition_point(|r| r.t_s <= t + 1e-9);
            readings.get(k)
        };
        let gyro_at = |t: f64| same_interval(t).map_or([0.0; 3], |r| r.gyro);
        let forced: Vec<Reading> = run
            .messages()?
            .iter()
            .filter(|m| m.topic == FORCE_TOPIC)
            .map(|m| {
                let t_s = m.stamp_ns() as f64 * 1e-9;
                let f = v3(&m.json["sensors"][0]["force"]);
                Reading {
                    t_s,
                    accel: f.map(|c| c / TEST_MASS_KG),
                    gyro: gyro_at(t_s),
                }
            })
            .collect();
        // Where the two designs part: per phase, the largest difference at one instant (the
        // finite difference measures the body's own motion, so this is the force sensor's
        // error as a measurement of it), and when.
        let diffs: Vec<(f64, f64)> = windows
            .iter()
            .map(|p| {
                forced
                    .iter()
                    .filter(|f| f.t_s >= p.from_s && f.t_s <= p.to_s)
                    .filter_map(|f| {
                        let r = same_interval(f.t_s)?;
                        let d = (0..3)
                            .map(|k| (f.accel[k] - r.accel[k]).abs())
                            .fold(0.0, f64::max);
                        Some((d, f.t_s))
                    })
                    .fold((0.0, 0.0), |a, b| if b.0 > a.0 { b } else { a })
            })
            .collect();
        let (diff, diff_t) = diffs
            .iter()
            .fold((0.0, 0.0), |a, &b| if b.0 > a.0 { b } else { a });
        let force_phases: Vec<PhaseErrors> = if forced.is_empty() {
            Vec::new()
        } else {
            force_plot(&run.dir.join(FORCE_PLOT_FILE), &readings, &forced, &windows)?;
            windows.iter().map(|p| score(p, &forced)).collect()
        };
        let accel = phases
            .iter()
            .map(PhaseErrors::accel_max)
            .fold(0.0, f64::max);
        let gyro = phases.iter().map(PhaseErrors::gyro_max).fold(0.0, f64::max);
        let scored = phases.iter().all(|p| p.readings > 0);
        let within = scored && accel <= ACCEL_TARGET_M_S2 && gyro <= GYRO_TARGET_RAD_S;
        let json = serde_json::json!({
            "scenario": self.scenario.name(),
            "readings": readings.len(),
            "phases": phases,
            "accel_max_err_m_s2": accel,
            "gyro_max_err_rad_s": gyro,
            "accel_target_m_s2": ACCEL_TARGET_M_S2,
            "gyro_target_rad_s": GYRO_TARGET_RAD_S,
            "within_target": within,
            "plot": PLOT_FILE,
            "force_sensor": if forced.is_empty() { serde_json::Value::Null } else { serde_json::json!({
                "readings": forced.len(),
                "max_diff_from_finite_difference_m_s2": diff,
                "max_diff_at_s": diff_t,
                "max_diff_per_phase_m_s2": diffs.iter().map(|d| d.0).collect::<Vec<_>>(),
                "test_mass_kg": TEST_MASS_KG,
                "phases": force_phases,
                "plot": FORCE_PLOT_FILE,
                "accel_max_err_m_s2": force_phases
                    .iter()
                    .map(PhaseErrors::accel_max)
                    .fold(0.0, f64::max),
            }) },
        });
        Ok(vec![Section {
            name: "imu".into(),
            json,
            markdown: markdown(self.scenario.name(), &phases, within, &force_phases, &diffs),
        }])
    }
}

/// The vertical specific force of both designs and the ideal one of each phase.
fn force_plot(
    path: &std::path::Path,
    readings: &[Reading],
    forced: &[Reading],
    phases: &[crate::scenario::Phase],
) -> anyhow::Result<()> {
    use crate::scenario::Expect;
    use caravan_report::plot::{Panel, Series, lines_svg};
    let z = |rs: &[Reading]| vec![rs.iter().map(|r| (r.t_s, r.accel[2])).collect()];
    let ideal = phases
        .iter()
        .filter_map(|p| match p.accel {
            Expect::Vector(f) => Some(vec![(p.from_s, f[2]), (p.to_s, f[2])]),
            Expect::Norm(_) => None,
        })
        .collect();
    let series = |label: &str, segments| Series {
        label: label.into(),
        segments,
    };
    lines_svg(
        path,
        "The two accelerometer designs: vertical specific force",
        &[Panel {
            y_label: "f z (m/s²)".into(),
            series: vec![
                series("finite difference", z(readings)),
                series("force sensor, F/m", z(forced)),
                series("ideal (scored windows)", ideal),
            ],
        }],
    )
}

fn markdown(
    scenario: &str,
    phases: &[PhaseErrors],
    within: bool,
    force_phases: &[PhaseErrors],
    diffs: &[(f64, f64)],
) -> String {
    let mut md = format!(
        "## IMU: {scenario}\n\nEvery reading against its phase's ideal value; targets \
         {ACCEL_TARGET_M_S2:.0e} m/s² and {GYRO_TARGET_RAD_S:.0e} rad/s: **{}**.\n\n\
         | phase | window (s) | readings | ideal f (m/s²) | max / RMS error f (m/s²) | ideal ω (rad/s) | max / RMS error ω (rad/s) |\n\
         |---|---|---:|---|---|---|---|\n",
        if within { "met" } else { "missed" }
    );
    let list = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:.4}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    for p in phases {
        let accel_max = p.accel_max();
        let accel_rms = p.accel_err_m_s2.iter().map(|s| s.rms).fold(0.0, f64::max);
        let gyro_rms = p.gyro_err_rad_s.iter().map(|s| s.rms).fold(0.0, f64::max);
        let ideal_f = if p.expected_accel_m_s2.len() == 1 {
            format!("\\|f\\| = {}", list(&p.expected_accel_m_s2))
        } else {
            format!("({})", list(&p.expected_accel_m_s2))
        };
        let _ = writeln!(
            md,
            "| {} | {:.2} – {:.2} | {} | {ideal_f} | {accel_max:.1e} / {accel_rms:.1e} | ({}) | {:.1e} / {gyro_rms:.1e} |",
            p.phase,
            p.from_s,
            p.to_s,
            p.readings,
            list(&p.expected_gyro_rad_s),
            p.gyro_max(),
        );
    }
    if force_phases.iter().any(|p| p.readings > 0) {
        let _ = write!(
            md,
            "\nThe accelerometer the reference study rejected, a {TEST_MASS_KG} kg test mass on a \
             force sensor (a = F/m), against the ideal value and against the finite-difference \
             reading of the same step (the body's own motion):\n\n\
             | phase | readings | max / RMS error f (m/s²) | max \\|F/m − finite difference\\| (m/s²) | at (s) |\n\
             |---|---:|---|---|---:|\n"
        );
        for (p, (d, t)) in force_phases.iter().zip(diffs) {
            let rms = p.accel_err_m_s2.iter().map(|s| s.rms).fold(0.0, f64::max);
            let _ = writeln!(
                md,
                "| {} | {} | {:.1e} / {rms:.1e} | {d:.1e} | {t:.3} |",
                p.phase,
                p.readings,
                p.accel_max()
            );
        }
        let _ = writeln!(md, "\n![The two accelerometer designs]({FORCE_PLOT_FILE})");
    }
    let _ = write!(md, "\n![IMU readings against time]({PLOT_FILE})\n");
    md
}

/// The spin-up section: the bar's analytic time against the measured ones and, for a row of
/// the reference's table, the paper's. JSON: `{scenario, torque_nm, rate_deg_s, mass_kg,
/// inertia_kg_m2, step_s, analytic_s, fit_s, fit_err_s, threshold_s, threshold_err_s,
/// within_one_step, paper_s, paper_err_s}`.
fn spin_up_section(bar: &Bar, readings: &[Reading]) -> anyhow::Result<Section> {
    let step_s = readings
        .windows(2)
        .map(|w| w[1].t_s - w[0].t_s)
        .fold(f64::INFINITY, f64::min);
    let gyro: Vec<(f64, f64)> = readings.iter().map(|r| (r.t_s, r.gyro[2])).collect();
    let m = spin_up::measure(&gyro, bar.rate_rad_s, step_s).ok_or_else(|| {
        anyhow::anyhow!("the gyro never ramped from 10 % to 90 % of the target rate")
    })?;
    let analytic = bar.analytic_s();
    let fit_err = m.fit_s - analytic;
    let threshold_err = m.threshold_s.map(|t| t - analytic);
    let rate_deg_s = bar.rate_rad_s.to_degrees();
    let paper = spin_up::reference_row(bar.torque_nm, rate_deg_s, bar.mass_kg);
    let within = fit_err.abs() <= step_s;
    // The IMU rides on the joint's axis, so whatever the bar does it reads (0, 0, g): x along
    // the bar (radial), y tangential. The gyro ramps, and is timed above instead.
    let on_axis = score(
        &crate::scenario::Phase {
            name: "on the axis",
            from_s: crate::scenario::SETTLE_S,
            to_s: f64::INFINITY,
            accel: crate::scenario::Expect::Vector([0.0, 0.0, crate::scenario::G]),
            gyro: [0.0; 3],
        },
        readings,
    );
    let accel_err = on_axis
        .accel_err_m_s2
        .iter()
        .map(|s| s.max)
        .collect::<Vec<_>>();
    let accel_within = on_axis.accel_max() <= ACCEL_TARGET_M_S2;
    let json = serde_json::json!({
        "scenario": "spinup",
        "torque_nm": bar.torque_nm,
        "rate_deg_s": rate_deg_s,
        "mass_kg": bar.mass_kg,
        "inertia_kg_m2": bar.inertia_kg_m2,
        "step_s": step_s,
        "analytic_s": analytic,
        "start_s": m.start_s,
        "fit_s": m.fit_s,
        "fit_err_s": fit_err,
        "threshold_s": m.threshold_s,
        "threshold_err_s": threshold_err,
        "ramp_readings": m.ramp_readings,
        "within_one_step": within,
        "paper_s": paper.map(|p| p.paper_s),
        "paper_err_s": paper.map(|p| p.paper_err_s),
        "accel_readings": on_axis.readings,
        "accel_max_err_m_s2": on_axis.accel_max(),
        "accel_err_xyz_m_s2": accel_err,
        "tangential_max_err_m_s2": accel_err[1],
        "accel_target_m_s2": ACCEL_TARGET_M_S2,
        "accel_within_target": accel_within,
        "plot": PLOT_FILE,
    });
    let opt =
        |v: Option<f64>, digits: usize| v.map_or("–".to_string(), |v| format!("{v:.digits$}"));
    let markdown = format!(
        "## IMU: spin-up\n\nM = {} N·m, ω = {rate_deg_s:.1} °/s, m = {} kg, I = {:.4} kg·m², \
         step {:.1} ms. Fit: a line through the gyro readings between 10 % and 90 % of ω; \
         threshold: the first reading within {:.0e} of ω. Error within one step: **{}**.\n\n\
         | analytic I·ω/M (s) | fit (s) | fit error (s) | threshold (s) | threshold error (s) | paper (s) | paper's error (s) |\n\
         |---:|---:|---:|---:|---:|---:|---:|\n\
         | {analytic:.4} | {:.4} | {fit_err:.1e} | {} | {} | {} | {} |\n\n\
         The IMU rides on the axis, so it reads f = (0, 0, g) throughout: largest error over \
         {} readings from {:.2} s, radial / tangential / vertical {:.1e} / {:.1e} / {:.1e} \
         m/s², target {ACCEL_TARGET_M_S2:.0e}: **{}**.\n\n\
         ![IMU readings against time]({PLOT_FILE})\n",
        bar.torque_nm,
        bar.mass_kg,
        bar.inertia_kg_m2,
        step_s * 1e3,
        spin_up::THRESHOLD,
        if within { "yes" } else { "no" },
        m.fit_s,
        opt(m.threshold_s, 4),
        threshold_err.map_or("–".into(), |e| format!("{e:.1e}")),
        opt(paper.map(|p| p.paper_s), 3),
        opt(paper.map(|p| p.paper_err_s), 3),
        on_axis.readings,
        crate::scenario::SETTLE_S,
        accel_err[0],
        accel_err[1],
        accel_err[2],
        if accel_within { "met" } else { "missed" },
    );
    Ok(Section {
        name: "imu".into(),
        json,
        markdown,
    })
}

/// The Allan section: the x axis of each triad's readings, its Allan deviation, and the noise
/// density and bias instability read off it against the configured ones. JSON: `{scenario,
/// readings, seconds, rate_hz, triads: [TriadResult], within_10_percent, plot}`.
fn allan_section(
    errors: &caravan_sensor::imu_errors::ImuErrors,
    readings: &[Reading],
    dir: &std::path::Path,
) -> anyhow::Result<Section> {
    let step_s = readings
        .windows(2)
        .map(|w| w[1].t_s - w[0].t_s)
        .fold(f64::INFINITY, f64::min);
    if readings.len() < 1000 || !step_s.is_finite() || step_s <= 0.0 {
        anyhow::bail!(
            "the Allan check needs at least 1000 evenly spaced IMU readings, got {}",
            readings.len()
        );
    }
    let accel: Vec<f64> = readings.iter().map(|r| r.accel[0]).collect();
    let gyro: Vec<f64> = readings.iter().map(|r| r.gyro[0]).collect();
    let triads = crate::allan_run::analyse(errors, step_s, &accel, &gyro);
    crate::plot::allan_svg(&dir.join(ALLAN_PLOT_FILE), &triads)?;
    let within = triads
        .iter()
        .all(|t| t.noise_density_err_rel.abs() <= 0.1 && t.bias_instability_err_rel.abs() <= 0.1);
    let seconds = readings.len() as f64 * step_s;
    let json = serde_json::json!({
        "scenario": "allan",
        "readings": readings.len(),
        "seconds": seconds,
        "rate_hz": 1.0 / step_s,
        "bias_correlation_s": errors.bias_correlation_s,
        "triads": triads,
        "within_10_percent": within,
        "plot": ALLAN_PLOT_FILE,
    });
    let mut md = format!(
        "## IMU: Allan deviation\n\n{} static readings over {seconds:.0} s at {:.0} Hz, x axis \
         of each triad; flicker correlation {:?} s. Both parameters within 10 %: **{}**.\n\n\
         | triad | noise density N: configured / read off | error | bias instability B: configured / read off | error |\n\
         |---|---|---:|---|---:|\n",
        readings.len(),
        1.0 / step_s,
        errors.bias_correlation_s,
        if within { "yes" } else { "no" }
    );
    for t in &triads {
        let _ = writeln!(md, "| {} |", t.cells().join(" | "));
    }
    let _ = write!(md, "\n![Allan deviation]({ALLAN_PLOT_FILE})\n");
    Ok(Section {
        name: "imu".into(),
        json,
        markdown: md,
    })
}
