//! The evaluation scenarios of the reference: training on a fixed head-on encounter, then S1
//! (the opponent's start shifted in y and z, flying straight), S2 (shifted start, zigzag), S3
//! (shifted start, pursuit). Starts are drawn from the episode's seed.

use crate::encounter::Encounter;
use crate::opponent::Opponent;
use caravan_sensor::noise::Gaussian;
use serde::{Deserialize, Serialize};

/// A scenario: how the opponent starts and flies.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// The opponent's start is shifted by Δy, Δz drawn uniformly in ±`offset_m`, m ≥ 0
    /// (0: exactly head-on).
    pub offset_m: f64,
    pub opponent: Opponent,
}

/// Half-width of the start shifts of S1–S3, m: as large as the collision radius, so that an
/// agent that holds its line still collides in many episodes.
pub const OFFSET_M: f64 = 0.5;

impl Scenario {
    /// The training scenario: head-on, straight.
    pub const HEAD_ON: Scenario = Scenario {
        offset_m: 0.0,
        opponent: Opponent::Straight,
    };

    /// The reference's scenarios by name: `head_on`, `s1`, `s2`, `s3`.
    pub fn named(name: &str) -> Result<Scenario, String> {
        Ok(match name {
            "head_on" => Self::HEAD_ON,
            "s1" => Scenario {
                offset_m: OFFSET_M,
                opponent: Opponent::Straight,
            },
            "s2" => Scenario {
                offset_m: OFFSET_M,
                opponent: Opponent::Zigzag {
                    amplitude_m: 1.0,
                    period_s: 4.0,
                },
            },
            "s3" => Scenario {
                offset_m: OFFSET_M,
                opponent: Opponent::Pursuit {
                    gain: 1.0,
                    v_max_m_s: 0.8,
                },
            },
            other => {
                return Err(format!(
                    "scenario '{other}' is not one of head_on, s1, s2, s3"
                ));
            }
        })
    }

    pub fn validate(&self) -> Result<(), String> {
        if !(self.offset_m.is_finite() && self.offset_m >= 0.0) {
            return Err(format!("'offset_m' must be ≥ 0, got {}", self.offset_m));
        }
        self.opponent.validate()
    }

    /// The opponent's start shift (Δy, Δz) of one episode.
    pub fn offset(&self, g: &mut Gaussian) -> [f64; 2] {
        [(), ()].map(|_| (2.0 * g.uniform() - 1.0) * self.offset_m)
    }
}

/// Checks the params a scenario's processes share: the encounter's constants and the
/// scenario's name.
pub fn checked(encounter: &Encounter, scenario: &str) -> Result<Scenario, String> {
    encounter.validate()?;
    Scenario::named(scenario).map_err(|e| format!("key 'scenario': {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shifts_stay_within_the_offset_and_head_on_has_none() {
        let mut g = Gaussian::new(4, 0);
        let s1 = Scenario::named("s1").unwrap();
        for _ in 0..1000 {
            let [y, z] = s1.offset(&mut g);
            assert!(y.abs() <= OFFSET_M && z.abs() <= OFFSET_M);
        }
        assert_eq!(Scenario::HEAD_ON.offset(&mut g), [0.0, 0.0]);
        assert!(Scenario::named("s4").is_err());
    }
}
