//! The scripted opponents: each flies −x at the encounter's speed and moves sideways by its
//! own law. The reference names them (straight, a zigzag with frequent sideways shifts, active
//! pursuit) without numbers; these are chosen and parameters.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// An opponent's lateral behaviour.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Opponent {
    /// Straight along −x.
    Straight,
    /// A triangle wave in y about its start: it moves at 4·A/P sideways, turning every half
    /// period (the first half toward +y).
    Zigzag {
        /// Peak sideways displacement, m, > 0.
        #[serde(default = "amplitude")]
        amplitude_m: f64,
        /// s, > 0.
        #[serde(default = "period")]
        period_s: f64,
    },
    /// Steers its y and z toward the agent's: v = gain·(agent − own), at most `v_max` per axis.
    Pursuit {
        /// 1/s, > 0.
        #[serde(default = "gain")]
        gain: f64,
        /// m/s, > 0.
        #[serde(default = "pursuit_v_max")]
        v_max_m_s: f64,
    },
}

fn amplitude() -> f64 {
    1.0
}
fn period() -> f64 {
    4.0
}
fn gain() -> f64 {
    1.0
}
fn pursuit_v_max() -> f64 {
    0.8
}

impl Opponent {
    pub fn validate(&self) -> Result<(), String> {
        let ok = |x: f64| x.is_finite() && x > 0.0;
        match *self {
            Opponent::Straight => Ok(()),
            Opponent::Zigzag {
                amplitude_m,
                period_s,
            } if ok(amplitude_m) && ok(period_s) => Ok(()),
            Opponent::Pursuit { gain, v_max_m_s } if ok(gain) && ok(v_max_m_s) => Ok(()),
            other => Err(format!("opponent {other:?}: every number must be positive")),
        }
    }

    /// Its velocity at `t_s` into the episode, at `own`, with the agent at `agent`.
    pub fn velocity(
        &self,
        speed_m_s: f64,
        t_s: f64,
        own: &Vector3<f64>,
        agent: &Vector3<f64>,
    ) -> Vector3<f64> {
        let lateral = match *self {
            Opponent::Straight => [0.0, 0.0],
            Opponent::Zigzag {
                amplitude_m,
                period_s,
            } => {
                // Quarter period out, half back, quarter out again: a triangle about 0.
                let phase = (t_s / period_s + 0.25).rem_euclid(1.0);
                let v = 4.0 * amplitude_m / period_s;
                [if phase < 0.5 { v } else { -v }, 0.0]
            }
            Opponent::Pursuit { gain, v_max_m_s } => {
                let steer = |d: f64| (gain * d).clamp(-v_max_m_s, v_max_m_s);
                [steer(agent.y - own.y), steer(agent.z - own.z)]
            }
        };
        Vector3::new(-speed_m_s, lateral[0], lateral[1])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_zigzag_is_a_triangle_wave_of_its_amplitude() {
        let z = Opponent::Zigzag {
            amplitude_m: 1.0,
            period_s: 4.0,
        };
        let (dt, mut y, mut lo, mut hi) = (1e-3, 0.0f64, 0.0f64, 0.0f64);
        for k in 0..8000 {
            y += z
                .velocity(1.0, k as f64 * dt, &Vector3::zeros(), &Vector3::zeros())
                .y
                * dt;
            lo = lo.min(y);
            hi = hi.max(y);
        }
        assert!(
            (hi - 1.0).abs() < 2e-3 && (lo + 1.0).abs() < 2e-3,
            "{lo} {hi}"
        );
        assert!(y.abs() < 2e-3, "back at the start after two periods: {y}");
    }

    #[test]
    fn a_pursuer_steers_toward_the_agent_within_its_speed() {
        let p = Opponent::Pursuit {
            gain: 1.0,
            v_max_m_s: 0.8,
        };
        let v = p.velocity(
            1.0,
            0.0,
            &Vector3::new(5.0, 0.0, 2.0),
            &Vector3::new(3.0, 0.3, 0.0),
        );
        assert!((v - Vector3::new(-1.0, 0.3, -0.8)).norm() < 1e-12, "{v}");
        assert_eq!(
            Opponent::Straight.velocity(2.0, 3.0, &Vector3::zeros(), &Vector3::x()),
            Vector3::new(-2.0, 0.0, 0.0)
        );
    }
}
