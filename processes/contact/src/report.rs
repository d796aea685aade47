//! The `contact` report section: the live estimates scored against the pushes applied
//! ([`crate::live`]), beside a Monte-Carlo of the same arm in the same pose at the same noise
//! (the run's pose from its last joint state, the links it pushed), and `contact.svg`.
//!
//! JSON: `{sigma, settle_s, live: LiveScore, monte_carlo: Row, within_monte_carlo}`;
//! `within_monte_carlo` holds when the live mean force, direction and point errors are each at
//! most the Monte-Carlo's 95th percentile.

use crate::arm_urdf::ArmModel;
use crate::live::{AppliedPush, EstimateAt, LinkPoses, score};
use crate::messages::ContactEstimate;
use crate::monte_carlo::{Config, run_level};
use crate::range::{MAX_MU, MAX_REPORT_TRIALS, MAX_TIME_S, MAX_TORQUE_NOISE_N_M, between};
use crate::scenario::ArmParams;
use crate::table::{Mean, row};
use caravan_report::{Inputs, ReportPlugin, Run, Section};
use caravan_schemas::Wrench;
use nalgebra::{Isometry2, Point2, Quaternion, UnitQuaternion, Vector2};
use serde::Deserialize;
use serde_json::Value;

/// The plot, in the run directory.
pub const PLOT_FILE: &str = "contact.svg";

#[derive(Debug, Clone, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Params {
    pub arm: ArmParams,
    /// The perception's torque noise σ, N·m, 0 to 20 (`estimator.torque_sigma`).
    pub sigma: f64,
    /// Estimates this long after a push begins or ends are left out, s, 0 to 86 400: the
    /// position loops take about 0.75 s to bring the arm to rest again (before, the torques
    /// carry the arm's inertia, not only the push).
    #[serde(default = "settle")]
    pub settle_s: f64,
    /// Friction coefficient of the pushes, 0 to 5.
    #[serde(default = "mu")]
    pub mu: f64,
    /// Monte-Carlo trials at the run's pose, 1 to 100 000.
    #[serde(default = "trials")]
    pub monte_carlo_trials: usize,
}

fn settle() -> f64 {
    0.75
}
fn mu() -> f64 {
    0.5
}
fn trials() -> usize {
    2000
}

pub struct ContactReport {
    p: Params,
    model: ArmModel,
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

fn planar(pose: &Value) -> Isometry2<f64> {
    let p = &pose["position"];
    let o = &pose["orientation"];
    let q = UnitQuaternion::from_quaternion(Quaternion::new(
        num(&o["w"]),
        num(&o["x"]),
        num(&o["y"]),
        num(&o["z"]),
    ));
    Isometry2::new(Vector2::new(num(&p["x"]), num(&p["y"])), q.euler_angles().2)
}

impl ReportPlugin for ContactReport {
    type Params = Params;

    fn new(p: Params, inputs: &Inputs) -> Result<Self, String> {
        between("sigma", p.sigma, 0.0, MAX_TORQUE_NOISE_N_M, "N·m")?;
        between("settle_s", p.settle_s, 0.0, MAX_TIME_S, "s")?;
        between("mu", p.mu, 0.0, MAX_MU, "")?;
        if !(1..=MAX_REPORT_TRIALS).contains(&p.monte_carlo_trials) {
            return Err(format!(
                "key 'monte_carlo_trials': must be between 1 and {MAX_REPORT_TRIALS}, got {}",
                p.monte_carlo_trials
            ));
        }
        let model = p.arm.load(&inputs.path(&p.arm.urdf))?;
        Ok(Self { p, model })
    }

    fn sections(&self, run: &Run) -> anyhow::Result<Vec<Section>> {
        let (mut pushes, mut poses, mut estimates) =
            (Vec::<AppliedPush>::new(), Vec::new(), Vec::new());
        let mut q_last: Option<Vec<f64>> = None;
        for m in run.messages()? {
            let t_s = m.stamp_ns() as f64 * 1e-9;
            let j = &m.json;
            match m.topic.as_str() {
                "robot/0/wrench" => {
                    let link = j["link"].as_str().unwrap_or_default().to_string();
                    if let Some(open) = pushes
                        .iter_mut()
                        .find(|p| p.link == link && p.end_s.is_infinite())
                    {
                        open.end_s = t_s;
                    }
                    let f = Vector2::new(num(&j["force"]["x"]), num(&j["force"]["y"]));
                    if j["frame"].as_u64() == Some(Wrench::LINK as u64) && f.norm() > 0.0 {
                        pushes.push(AppliedPush {
                            start_s: t_s,
                            end_s: f64::INFINITY,
                            link,
                            local_point: Point2::new(num(&j["point"]["x"]), num(&j["point"]["y"])),
                            local_force: f,
                        });
                    }
                }
                "robot/0/link_states" => poses.push(LinkPoses {
                    t_s,
                    poses: j["links"]
                        .as_array()
                        .into_iter()
                        .flatten()
                        .map(|l| {
                            (
                                l["name"].as_str().unwrap_or_default().to_string(),
                                planar(&l["pose"]),
                            )
                        })
                        .collect(),
                }),
                "robot/0/joint_states" => {
                    let joints = j["joints"].as_array().cloned().unwrap_or_default();
                    q_last = self
                        .model
                        .joints
                        .iter()
                        .map(|n| {
                            joints
                                .iter()
                                .find(|v| v["name"] == n.as_str())
                                .map(|v| num(&v["position"]))
                        })
                        .collect();
                }
                "robot/0/contact_estimate" => {
                    let v2 = |v: &Value| {
                        let (x, y) = (num(&v["x"]), num(&v["y"]));
                        (x.is_finite() && y.is_finite()).then(|| Vector2::new(x, y))
                    };
                    estimates.push(EstimateAt {
                        t_s,
                        status: j["status"]
                            .as_u64()
                            .unwrap_or(ContactEstimate::NO_SOLUTION as u64)
                            as u32,
                        link: j["link"].as_str().unwrap_or_default().to_string(),
                        force: v2(&j["force"]),
                        point: v2(&j["point"]).map(Point2::from),
                    });
                }
                _ => {}
            }
        }
        if pushes.is_empty() || estimates.is_empty() {
            anyhow::bail!(
                "the recording needs robot/0/wrench pushes and robot/0/contact_estimate estimates"
            );
        }
        let q = q_last.ok_or_else(|| {
            anyhow::anyhow!("no robot/0/joint_states with the arm's joints in the recording")
        })?;
        let (live, plotted) = score(&pushes, &poses, &estimates, self.p.settle_s);
        let mut links: Vec<usize> = pushes
            .iter()
            .filter_map(|p| self.model.links.iter().position(|l| *l == p.link))
            .collect();
        links.sort_unstable();
        links.dedup();
        let mut config = Config::reference();
        config.arm = self.model.arm.clone();
        config.joint_limits = q.iter().map(|q| (*q, *q)).collect();
        config.min_bend = 0.0;
        config.push.links = links;
        config.push.mu = self.p.mu;
        config.trials = self.p.monte_carlo_trials;
        config.optimiser_trials = 0;
        let mc = row(self.p.sigma, &run_level(&config, self.p.sigma));
        let within = |live: &Option<Mean>, mc: &Option<Mean>| match (live, mc) {
            (Some(l), Some(m)) => l.mean <= m.p95,
            _ => false,
        };
        let within_monte_carlo = within(&live.force_error_n, &mc.force_error_n)
            && within(&live.direction_error_deg, &mc.direction_error_deg)
            && within(&live.point_error_mm, &mc.point_error_mm);
        crate::plot::contact_svg(&run.dir.join(PLOT_FILE), self.p.sigma, &plotted)?;
        let markdown = markdown(self.p.sigma, &live, &mc, within_monte_carlo);
        Ok(vec![Section {
            name: "contact".into(),
            json: serde_json::json!({
                "sigma": self.p.sigma,
                "settle_s": self.p.settle_s,
                "live": live,
                "monte_carlo": mc,
                "within_monte_carlo": within_monte_carlo,
                "plot": PLOT_FILE,
            }),
            markdown,
        }])
    }
}

fn markdown(
    sigma: f64,
    live: &crate::live::LiveScore,
    mc: &crate::table::Row,
    within: bool,
) -> String {
    let cell = |m: &Option<Mean>| {
        m.as_ref().map_or("–".into(), |m| {
            format!("{:.3} [{:.3}, {:.3}]", m.mean, m.ci95[0], m.ci95[1])
        })
    };
    let p95 = |m: &Option<Mean>| m.as_ref().map_or("–".into(), |m| format!("{:.3}", m.p95));
    let mut s = format!(
        "## Contact identification\n\n{} pushes, {} settled estimates scored (torque noise σ = {sigma} N·m). \
         Live against a Monte-Carlo of {} trials in the same pose: **{}**.\n\n\
         | metric | live mean [95 % CI] | Monte-Carlo mean [95 % CI] | Monte-Carlo p95 |\n|---|---|---|---|\n",
        live.pushes,
        live.scored,
        mc.trials,
        if within { "within" } else { "outside" }
    );
    for (name, l, m) in [
        ("force error (N)", &live.force_error_n, &mc.force_error_n),
        (
            "direction error (°)",
            &live.direction_error_deg,
            &mc.direction_error_deg,
        ),
        ("point error (mm)", &live.point_error_mm, &mc.point_error_mm),
    ] {
        s += &format!("| {name} | {} | {} | {} |\n", cell(l), cell(m), p95(m));
    }
    s += &format!(
        "| no solution (%) | {:.2} | {:.2} | |\n| wrong link (%) | {:.2} | {:.2} | |\n\n\
         Between pushes {:.2} % of {} estimates reported a contact. Plot: [{PLOT_FILE}]({PLOT_FILE}).\n",
        live.no_solution_pct,
        mc.no_solution_pct,
        live.wrong_link_pct,
        mc.wrong_link_pct,
        live.false_contact_pct,
        live.between_pushes
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// The report's params with `over` over the shipped ones; the arm's URDF is not read
    /// before the numbers are checked.
    fn new(over: Value) -> Result<(), String> {
        let mut p = json!({ "arm": { "urdf": "none.urdf" }, "sigma": 0.1, "settle_s": 0.75 });
        p.as_object_mut()
            .unwrap()
            .extend(over.as_object().unwrap().clone());
        let p: Params = serde_json::from_value(p).unwrap();
        let inputs = Inputs {
            launch_dir: ".".into(),
        };
        ContactReport::new(p, &inputs).map(|_| ())
    }

    #[test]
    fn report_params_out_of_range_are_named_before_the_urdf_is_read() {
        assert!(new(json!({})).unwrap_err().contains("none.urdf"));
        for (bad, key) in [
            (json!({ "sigma": 1e308 }), "sigma"),
            (json!({ "settle_s": 1e308 }), "settle_s"),
            (json!({ "mu": f64::MAX }), "mu"),
            (
                json!({ "monte_carlo_trials": 4_000_000_000u64 }),
                "monte_carlo_trials",
            ),
            (json!({ "monte_carlo_trials": 0 }), "monte_carlo_trials"),
            (
                json!({ "arm": { "urdf": "none.urdf", "link_radius": 1e308 } }),
                "arm.link_radius",
            ),
        ] {
            let e = new(bad.clone()).unwrap_err();
            assert!(e.starts_with(&format!("key '{key}'")), "{bad}: {e}");
        }
    }
}
