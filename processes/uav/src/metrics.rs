//! What the reference never measured, per episode: closest approach, deviation from the start
//! line, path length, time to pass, action smoothness and the agent's reaction latency.

use crate::encounter::{Encounter, State};

/// Accumulates one episode's measures, step by step.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EpisodeMetrics {
    /// Least centre distance between the drones, m.
    pub closest_m: f64,
    /// Largest and summed distance of the agent from its start line (|Δy| + |Δz|), m.
    pub max_deviation_m: f64,
    deviation_sum: f64,
    samples: u32,
    /// Length of the agent's path, m.
    pub path_m: f64,
    /// When the agent's x first passed the opponent's, s into the episode.
    pub pass_s: Option<f64>,
    /// Sum of |a_k − a_{k−1}| (action units per step) and how many differences it holds.
    smoothness_sum: f64,
    smoothness_n: u32,
    last_units: Option<[f64; 2]>,
    /// Sum and count of the reaction latencies (observation to its action arriving), s.
    latency_sum: f64,
    latency_n: u32,
    last: Option<State>,
}

impl EpisodeMetrics {
    pub fn new() -> Self {
        Self {
            closest_m: f64::INFINITY,
            ..Self::default()
        }
    }

    /// Takes the state after a step.
    pub fn observe(&mut self, e: &Encounter, s: &State) {
        self.closest_m = self.closest_m.min((s.opponent - s.agent).norm());
        let start = e.agent_start();
        let deviation = (s.agent.y - start.y).abs() + (s.agent.z - start.z).abs();
        self.max_deviation_m = self.max_deviation_m.max(deviation);
        self.deviation_sum += deviation;
        self.samples += 1;
        if let Some(last) = &self.last {
            self.path_m += (s.agent - last.agent).norm();
            if self.pass_s.is_none() && last.agent.x < last.opponent.x && s.agent.x >= s.opponent.x
            {
                self.pass_s = Some(s.t_s);
            }
        }
        self.last = Some(*s);
    }

    /// Takes an action (in units of dv along y and z) and how long after its observation it
    /// arrived, s.
    pub fn action(&mut self, units: [f64; 2], latency_s: f64) {
        if let Some([y, z]) = self.last_units {
            self.smoothness_sum += (units[0] - y).hypot(units[1] - z);
            self.smoothness_n += 1;
        }
        self.last_units = Some(units);
        self.latency_sum += latency_s;
        self.latency_n += 1;
    }

    /// The measures, named with their units, for an episode's summary.
    pub fn named(&self) -> Vec<(&'static str, f64)> {
        let mean = |sum: f64, n: u32| if n > 0 { sum / n as f64 } else { f64::NAN };
        vec![
            ("closest_m", self.closest_m),
            ("max_deviation_m", self.max_deviation_m),
            ("mean_deviation_m", mean(self.deviation_sum, self.samples)),
            ("path_m", self.path_m),
            ("pass_s", self.pass_s.unwrap_or(f64::NAN)),
            (
                "action_change",
                mean(self.smoothness_sum, self.smoothness_n),
            ),
            ("reaction_latency_s", mean(self.latency_sum, self.latency_n)),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn measures_of_a_hand_made_episode() {
        let e = Encounter::default();
        let mut m = EpisodeMetrics::new();
        let state = |t: f64, ax: f64, ay: f64, ox: f64| State {
            agent: Vector3::new(ax, ay, 2.0),
            agent_v: Vector3::zeros(),
            opponent: Vector3::new(ox, 0.0, 2.0),
            opponent_v: Vector3::zeros(),
            t_s: t,
        };
        m.observe(&e, &state(0.0, 0.0, 0.0, 10.0));
        m.observe(&e, &state(1.0, 4.0, 3.0, 6.0));
        m.observe(&e, &state(2.0, 8.0, 3.0, 2.0));
        m.action([0.0, 0.0], 0.001);
        m.action([1.0, 0.0], 0.003);
        m.action([1.0, 1.0], 0.002);
        let named: std::collections::BTreeMap<_, _> = m.named().into_iter().collect();
        assert!((named["closest_m"] - (4.0f64 + 9.0).sqrt()).abs() < 1e-12);
        assert_eq!(named["max_deviation_m"], 3.0);
        assert!((named["mean_deviation_m"] - 2.0).abs() < 1e-12);
        assert!((named["path_m"] - 9.0).abs() < 1e-12);
        assert_eq!(named["pass_s"], 2.0);
        assert!((named["action_change"] - 1.0).abs() < 1e-12);
        assert!((named["reaction_latency_s"] - 0.002).abs() < 1e-12);
    }
}
