//! Episodes of the encounter's own kinematics (both drones integrated at the agent's step):
//! what the rules and the baselines are checked against in unit tests. The scenario itself
//! runs the same rules over real processes and the physics.

use crate::encounter::{Encounter, Outcome, State};
use crate::policy::Policy;
use crate::scenario::Scenario;
use nalgebra::Vector3;

/// One episode from the opponent's start shift `offset`: its outcome, steps and return.
pub fn episode(
    e: &Encounter,
    scenario: &Scenario,
    offset: [f64; 2],
    policy: &mut dyn Policy,
) -> (Outcome, usize, f64) {
    policy.reset();
    let mut s = State {
        agent: e.agent_start(),
        agent_v: Vector3::new(e.speed_m_s, 0.0, 0.0),
        opponent: e.opponent_start(offset),
        opponent_v: Vector3::new(-e.speed_m_s, 0.0, 0.0),
        t_s: 0.0,
    };
    let (mut steps, mut total) = (0, 0.0);
    loop {
        let action = policy.act(&e.observe(&s));
        s.agent_v = e
            .apply(&s.agent_v, action)
            .expect("the policy's action is valid");
        s.opponent_v = scenario
            .opponent
            .velocity(e.speed_m_s, s.t_s, &s.opponent, &s.agent);
        s.agent += s.agent_v * e.step_s;
        s.opponent += s.opponent_v * e.step_s;
        s.t_s += e.step_s;
        steps += 1;
        let outcome = e.outcome(&s);
        total += e.reward(&s, outcome);
        if let Some(o) = outcome {
            return (o, steps, total);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::policy::{DoNothing, SideStep};
    use caravan_sensor::noise::Gaussian;

    #[test]
    fn doing_nothing_head_on_collides_and_the_side_step_passes_s1() {
        let e = Encounter::default();
        let (o, steps, total) = episode(&e, &Scenario::HEAD_ON, [0.0, 0.0], &mut DoNothing);
        assert_eq!(o, Outcome::Collided);
        // The centres close at 2 m/s from 10 m; at step 114 (4.75 s) they are exactly 0.5 m
        // apart, at step 115 less: collided. The line was held, so only the collision costs.
        assert_eq!(steps, 115);
        assert!((total + 1000.0).abs() < 1e-9, "{total}");
        let s1 = Scenario::named("s1").unwrap();
        let mut g = Gaussian::new(1, 0);
        let mut passed = 0;
        for _ in 0..1000 {
            let (o, _, _) = episode(&e, &s1, s1.offset(&mut g), &mut SideStep::new(&e));
            passed += (o == Outcome::Passed) as usize;
        }
        assert!(passed >= 990, "{passed} of 1000");
    }
}
