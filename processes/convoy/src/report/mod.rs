//! The convoy's report plugin (`caravan-convoy-report`): the `convoy` section (goals, gaps,
//! collisions, order, cross-track errors, `trajectories.svg`, `series.svg` with the gaps and
//! cross-track errors against time) and the `slam` section (map
//! scale on the world's surveys, the leader's pose error, `map.svg`).
//!
//! Params (in the launch file's `[[report]]` entry):
//!
//! | key | type | meaning |
//! |---|---|---|
//! | `world` | path | the world file, relative to the launch file: obstacles for the plots, surveys for the map scale |
//! | `urdf` | path | the robots' URDF: the chassis footprint for the gap |
//!
//! `report.json` gains:
//! - `convoy` (when the recording holds `robot/<i>/pose_true` of two or more robots and
//!   `goal`): `{robots, goals_total, goals_reached, goal_times_s[], min_gap_m, collisions,
//!   order_kept, followers[]: {robot, cross_track_to_predecessor_m, cross_track_to_leader_m}
//!   (each {mean, p95, max}), plot}`; definitions in `convoy.rs`.
//! - `slam` (when the run left a map or recorded `robot/0/pose`): `{pose_error_m: {mean, max,
//!   samples}, map_scale_error_pct[], surveys[]: {name, true_m, map_m, error_pct}, plot}`;
//!   definitions in `slam.rs`.

mod convoy;
mod markdown;
mod plot;
mod slam;

use caravan_report::{Inputs, ReportPlugin, Run, Section};
use convoy::{Footprint, Scene};
use serde::Deserialize;

/// The plugin's params.
#[derive(Debug, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The world file, relative to the launch file.
    pub world: String,
    /// The robots' URDF, relative to the launch file.
    pub urdf: String,
}

/// The convoy and SLAM sections of a convoy run.
pub struct ConvoyReport {
    scene: Scene,
}

impl ReportPlugin for ConvoyReport {
    type Params = Params;

    fn new(p: Params, inputs: &Inputs) -> Result<Self, String> {
        let world = caravan_world::load_world(&inputs.path(&p.world))
            .map_err(|e| format!("key 'world': world file {e}"))?;
        let robot = caravan_world::load_robot(&inputs.path(&p.urdf))
            .map_err(|e| format!("key 'urdf': robot description {e}"))?;
        Ok(Self {
            scene: Scene {
                world,
                footprint: Footprint::of(&robot),
            },
        })
    }

    fn sections(&self, run: &Run) -> anyhow::Result<Vec<Section>> {
        let messages = run.messages()?;
        let mut sections = Vec::new();
        if let Some(json) = convoy::section(messages, &self.scene, &run.dir) {
            sections.push(Section {
                name: "convoy".into(),
                markdown: markdown::convoy(&json),
                json,
            });
        }
        if let Some(json) = slam::section(messages, Some(&self.scene.world), &run.dir) {
            sections.push(Section {
                name: "slam".into(),
                markdown: markdown::slam(&json),
                json,
            });
        }
        Ok(sections)
    }
}
