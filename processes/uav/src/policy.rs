//! What an agent is: a policy from the 6-number observation to an action. The sanity
//! baselines of the reference live here; a learned policy implements the same trait.

use crate::encounter::{Action, Encounter};

/// A policy: one action per observation (see [`Encounter::observe`]).
pub trait Policy {
    fn act(&mut self, observation: &[f64; 6]) -> Action;
    /// A new episode begins.
    fn reset(&mut self) {}
}

/// Never changes its velocity: against a straight head-on opponent it must collide.
pub struct DoNothing;

impl Policy for DoNothing {
    fn act(&mut self, _: &[f64; 6]) -> Action {
        Action::Discrete(0)
    }
}

/// The scripted side-step: while the opponent is ahead and within `clearance_m` of its line
/// (in y and z), speed up sideways away from it; otherwise bring the sideways speed back to 0.
pub struct SideStep {
    /// Unscales the observation: the encounter's separation and velocity scale, m and m/s.
    separation_m: f64,
    velocity_scale_m_s: f64,
    dv_m_s: f64,
    /// m, > the collision radius.
    pub clearance_m: f64,
}

impl SideStep {
    /// Clears the collision radius by 0.3 m.
    pub fn new(e: &Encounter) -> Self {
        Self {
            separation_m: e.separation_m,
            velocity_scale_m_s: e.velocity_scale_m_s,
            dv_m_s: e.dv_m_s,
            clearance_m: e.collision_radius_m + 0.3,
        }
    }
}

impl Policy for SideStep {
    fn act(&mut self, o: &[f64; 6]) -> Action {
        let (vy, ahead) = (o[1] * self.velocity_scale_m_s, o[3] > 0.0);
        let (ry, rz) = (o[4] * self.separation_m, o[5] * self.separation_m);
        if ahead && ry.hypot(rz) < self.clearance_m {
            // Away from the opponent in y (+y when it is dead ahead).
            return Action::Discrete(if ry > 0.0 { 2 } else { 1 });
        }
        if vy > self.dv_m_s / 2.0 {
            Action::Discrete(2)
        } else if vy < -self.dv_m_s / 2.0 {
            Action::Discrete(1)
        } else {
            Action::Discrete(0)
        }
    }
}
