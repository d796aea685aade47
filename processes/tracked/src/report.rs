//! The `tracked` report section: the crossing's outcome (see [`crate::crossing`]), how far
//! and how fast the robot went, from the recorded `robot/0/ground_truth`, and its braking
//! distance after a stop asked on the recorded `robot/0/cmd_vel` (see [`crate::braking`]);
//! with `robot/0/contacts` recorded, the chassis' share of the contact force at the end (see
//! [`crate::resting`]).
//!
//! JSON: `{goal_x_m, outcome, passed, stuck, flipped, off_world, passed_at_s, max_x_m, max_tilt_deg, max_climb_m,
//! top_speed_m_s, stop_s, braking_distance_m, chassis_share, high_centred, samples, track}`.

use crate::crossing::{Outcome, Sample, classify};
use caravan_report::{Inputs, ReportPlugin, Run, Section};
use serde::Deserialize;

/// The ground-truth topic of the scenario's robot.
pub const TRUTH_TOPIC: &str = "robot/0/ground_truth";
/// The operator's velocity command to it.
pub const CMD_VEL_TOPIC: &str = "robot/0/cmd_vel";

#[derive(Debug, Clone, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The goal line: the run passes when the base's x reaches it, m, in
    /// [`crate::params::GOAL_X_M`], and with `world` on its floor, in (0, its length].
    pub goal_x_m: f64,
    /// The world file (relative to the launch file), for the picture of the terrain with
    /// the track driven and the floor plan a run can leave (outcome `off_world`); none: no
    /// picture, and a run is never off the world.
    #[serde(default)]
    pub world: Option<String>,
}

/// The picture of the terrain and the track, in the run directory.
pub const TERRAIN_PLOT_FILE: &str = "terrain.svg";

/// The samples thinned to one per `every_s`: `[t, x, y, z, tilt]`.
fn track(samples: &[Sample], every_s: f64) -> Vec<[f64; 5]> {
    let mut next = f64::NEG_INFINITY;
    let mut out = Vec::new();
    for s in samples {
        if s.t_s >= next {
            let [x, y, z] = s.position;
            out.push([s.t_s, x, y, z, s.tilt_deg()]);
            next = s.t_s + every_s - 1e-9;
        }
    }
    out
}

/// What the report takes from the world file.
struct Terrain {
    /// Its blocks, for the picture.
    grid: crate::rse::Grid,
    name: String,
    /// Its floor plan, m: a base outside [0, x] × [0, y] is off the world.
    size: [f64; 2],
}

/// A goal line on the world's floor, x in (0, `length_m`]: past its end the base leaves the
/// world (outcome `off_world`) before it could pass, so the run could never pass.
pub fn goal_on_floor(goal_x_m: f64, world: &str, length_m: f64) -> Result<(), String> {
    if goal_x_m > 0.0 && goal_x_m <= length_m {
        return Ok(());
    }
    Err(format!(
        "key 'goal_x_m': must lie on the floor of world {world}, above 0 and at most its \
         length {} m, got {}; a run could never reach it",
        crate::params::show_exact(length_m),
        crate::params::show_exact(goal_x_m)
    ))
}

pub struct TrackedReport {
    params: Params,
    /// When `world` is given.
    terrain: Option<Terrain>,
}

impl ReportPlugin for TrackedReport {
    type Params = Params;

    fn new(params: Params, inputs: &Inputs) -> Result<Self, String> {
        crate::params::GOAL_X_M.check("goal_x_m", params.goal_x_m)?;
        let terrain = match &params.world {
            Some(w) => {
                let world = caravan_world::world::load_world(&inputs.path(w))
                    .map_err(|e| format!("key 'world': {e}"))?;
                goal_on_floor(params.goal_x_m, w, world.size[0])?;
                Some(Terrain {
                    grid: crate::rse_world::grid_of(&world),
                    size: world.size,
                    name: world.name,
                })
            }
            None => None,
        };
        Ok(Self { params, terrain })
    }

    fn sections(&self, run: &Run) -> anyhow::Result<Vec<Section>> {
        let num = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
        let mut samples = Vec::new();
        let mut top_speed: f64 = 0.0;
        let messages = run.messages()?;
        let commands: Vec<(f64, f64)> = messages
            .iter()
            .filter(|m| m.topic == CMD_VEL_TOPIC)
            .map(|m| (m.stamp_ns() as f64 * 1e-9, num(&m.json["linear"]["x"])))
            .collect();
        for m in messages.iter().filter(|m| m.topic == TRUTH_TOPIC) {
            let p = &m.json["pose"]["position"];
            let q = &m.json["pose"]["orientation"];
            let v = &m.json["twist"]["linear"];
            top_speed = top_speed.max(num(&v["x"]).hypot(num(&v["y"])));
            samples.push(Sample {
                t_s: m.stamp_ns() as f64 * 1e-9,
                position: [num(&p["x"]), num(&p["y"]), num(&p["z"])],
                orientation: [num(&q["x"]), num(&q["y"]), num(&q["z"]), num(&q["w"])],
            });
        }
        let size = self.terrain.as_ref().map(|t| t.size);
        let c = classify(&samples, self.params.goal_x_m, size).ok_or_else(|| {
            anyhow::anyhow!(
                "no ground truth on {TRUTH_TOPIC} in the recording (physics `ground_truth = true`)"
            )
        })?;
        let contacts: Vec<crate::resting::Step> = messages
            .iter()
            .filter(|m| m.topic == crate::resting::CONTACTS_TOPIC)
            .map(|m| {
                let contacts = m.json["contacts"].as_array().map_or(&[][..], Vec::as_slice);
                crate::resting::Step::new(
                    m.stamp_ns() as f64 * 1e-9,
                    contacts
                        .iter()
                        .map(|c| (c["link"].as_str().unwrap_or(""), num(&c["normal_force"]))),
                )
            })
            .collect();
        let chassis_share = crate::resting::chassis_share(&contacts);
        // None: no contacts recorded.
        let high_centred = chassis_share
            .map(|share| crate::resting::high_centred(c.outcome == Outcome::Stuck, share));
        let stop_s = crate::braking::stop_time(&commands);
        let braking_m = stop_s.and_then(|t| crate::braking::braking_distance(&samples, t));
        let json = serde_json::json!({
            "goal_x_m": self.params.goal_x_m,
            "outcome": c.outcome,
            // One flag per outcome, so a sweep counts them with Wilson intervals.
            "passed": c.outcome == Outcome::Passed,
            "stuck": c.outcome == Outcome::Stuck,
            "flipped": c.outcome == Outcome::Flipped,
            "off_world": c.outcome == Outcome::OffWorld,
            "passed_at_s": c.passed_at_s,
            "max_x_m": c.max_x_m,
            "max_tilt_deg": c.max_tilt_deg,
            "max_climb_m": c.max_climb_m,
            "top_speed_m_s": top_speed,
            // When the operator asked for a stop, and how far the base went after it
            // (null: no stop, or still moving when the run ended).
            "stop_s": stop_s,
            "braking_distance_m": braking_m,
            // The chassis' share of the contact force over the last 5 s (null: no contacts
            // recorded).
            "chassis_share": chassis_share,
            "high_centred": high_centred,
            "samples": samples.len(),
            // Every 0.1 s: [t s, x, y, z m, tilt °], for plots and the terrain picture.
            "track": track(&samples, 0.1),
        });
        let mut markdown = format!(
            "## Tracked robot: crossing\n\nOutcome **{:?}** (goal line x = {} m{}). Furthest x \
             {:.3} m, highest climb {:.3} m, largest tilt {:.1}°, top speed {:.3} m/s.\n",
            c.outcome,
            self.params.goal_x_m,
            c.passed_at_s
                .map_or(String::new(), |t| format!(", reached at {t:.2} s")),
            c.max_x_m,
            c.max_climb_m,
            c.max_tilt_deg,
            top_speed
        );
        if let (Some(t), Some(d)) = (stop_s, braking_m) {
            markdown.push_str(&format!(
                "Stop asked at {t:.2} s: braking distance {d:.3} m.\n"
            ));
        }
        if let Some(share) = chassis_share {
            markdown.push_str(&format!(
                "Over the last {} s the chassis bears {:.0} % of the robot's contact force{}.\n",
                crate::resting::END_SPAN_S,
                100.0 * share,
                if high_centred == Some(true) {
                    ": stuck high-centred"
                } else {
                    ""
                }
            ));
        }
        if let Some(Terrain { grid, name, .. }) = &self.terrain {
            let path: Vec<(f64, f64)> = samples
                .iter()
                .map(|s| (s.position[0], s.position[1]))
                .collect();
            crate::rse_world::draw(
                grid,
                &[path],
                &format!("{name}: {:?}", c.outcome),
                &run.dir.join(TERRAIN_PLOT_FILE),
            )?;
            markdown.push_str(&format!("\n![terrain and track]({TERRAIN_PLOT_FILE})\n"));
        }
        Ok(vec![Section {
            name: "tracked".into(),
            json,
            markdown,
        }])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_goal_line_off_the_worlds_floor_is_refused() {
        assert!(goal_on_floor(5.5, "worlds/random-1.toml", 7.0).is_ok());
        assert!(goal_on_floor(7.0, "w.toml", 7.0).is_ok());
        for bad in [0.0, -1.0, 7.5, 1e300, f64::NAN] {
            let e = goal_on_floor(bad, "w.toml", 7.0).unwrap_err();
            assert!(
                e.starts_with("key 'goal_x_m': must lie on the floor of world w.toml"),
                "{e}"
            );
        }
    }

    #[test]
    fn a_goal_past_any_world_is_refused_without_one() {
        let inputs = Inputs {
            launch_dir: ".".into(),
        };
        let params = |goal_x_m: f64| Params {
            goal_x_m,
            world: None,
        };
        assert!(TrackedReport::new(params(5.0), &inputs).is_ok());
        for bad in [2e4, f64::INFINITY, f64::NAN] {
            let e = TrackedReport::new(params(bad), &inputs).err().unwrap();
            assert!(
                e.starts_with("key 'goal_x_m': must be between -10000 and 10000 m"),
                "{e}"
            );
        }
    }
}
