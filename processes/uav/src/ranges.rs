//! Physical ranges of the UAV processes' params, checked in each process's `setup` (so under
//! the launcher's check, before the group starts): every number finite, of its sign and within
//! what a small quadcopter's encounter has, so that a typo (`1e308`, `1e-300`, `nan`) is refused
//! with the key named (`key 'encounter.speed_m_s': must be between 0 and 40 m/s, got 1e308`)
//! instead of a run that never ends or a report of `inf`. Each bound's constant says why.

pub use caravan::range::{above, between, shown};

use crate::encounter::Encounter;
use crate::world::Frame;

/// The environment's and the opponent's tick, Hz: both step at the physics' 240 Hz
/// (PyBullet's step, `Trigger::every_hz(240.0)` in their binaries).
pub const TICK_HZ: f64 = 240.0;

/// The fastest forward, lateral or vertical speed, m/s: racing quadcopters reach about
/// 40 m/s; the reference's small quadcopters fly at 1 m/s.
pub const MAX_SPEED_M_S: f64 = 40.0;

/// The farthest start distance, m: beyond a kilometre two small drones are far out of each
/// other's detect-and-avoid range (tens to hundreds of metres), and the observation divides
/// positions by it, so every relative position would read as 0.
pub const MAX_SEPARATION_M: f64 = 1000.0;

/// The highest start altitude and floor, m: 120 m (400 ft) is the legal ceiling of small
/// drones in the EU's open category and under the US's Part 107.
pub const MAX_ALTITUDE_M: f64 = 120.0;

/// The largest collision radius (distance between centres), m: two large drones of 5 m each.
/// The reference's is 0.5 m (two 0.25 m spheres).
pub const MAX_COLLISION_RADIUS_M: f64 = 10.0;

/// The shortest agent step, s: one tick of the environment ([`TICK_HZ`]); a shorter step
/// cannot be kept, the environment acts at most once a tick.
pub const MIN_STEP_S: f64 = 1.0 / TICK_HZ;

/// The longest agent step, s: a policy acting less than once a second is no collision
/// avoidance loop (the reference's acts at 24 Hz).
pub const MAX_STEP_S: f64 = 1.0;

/// The velocity scale's range, m/s: observed velocities are divided by it and clipped to
/// ±1, so below 1 cm/s every velocity reads ±1, and above 100 m/s (2.5 times
/// [`MAX_SPEED_M_S`]) every velocity reads about 0.
pub const MIN_VELOCITY_SCALE_M_S: f64 = 0.01;
pub const MAX_VELOCITY_SCALE_M_S: f64 = 100.0;

/// The longest episode, s: an hour, longer than any small quadcopter's battery lasts
/// (20–40 min).
pub const MAX_TIME_LIMIT_S: f64 = 3600.0;

/// The largest terminal reward: a thousand times the reference's 1000. Larger only rescales
/// the returns a learner must then normalise; a negative one would reward colliding.
pub const MAX_TERMINAL_REWARD: f64 = 1e6;

/// The most episodes of one run: train.toml's 100 000 (a cap the learner ends the group
/// before) ten times over; a million episodes of up to [`MAX_TIME_LIMIT_S`] are years of
/// simulated time.
pub const MAX_EPISODES: u64 = 1_000_000;

/// The farthest the encounter's frame may sit from the world's origin, m: the largest extent
/// of a world (`caravan_world::limits::MAX_WORLD_EXTENT_M`, where f32 physics still resolves
/// about a millimetre).
pub const MAX_ORIGIN_M: f64 = 10_000.0;

/// Checks every number of the encounter (keys `encounter.*`): its range above, and the
/// relations between them that tie it to the tick.
pub fn encounter(e: &Encounter) -> Result<(), String> {
    let key = |k: &str| format!("encounter.{k}");
    above(&key("speed_m_s"), e.speed_m_s, 0.0, MAX_SPEED_M_S, "m/s")?;
    above(&key("v_max_m_s"), e.v_max_m_s, 0.0, MAX_SPEED_M_S, "m/s")?;
    // One action unit larger than the speed limit saturates it at once: no finer control.
    above(
        &key("dv_m_s"),
        e.dv_m_s,
        0.0,
        e.v_max_m_s,
        "m/s (v_max_m_s)",
    )?;
    between(
        &key("velocity_scale_m_s"),
        e.velocity_scale_m_s,
        MIN_VELOCITY_SCALE_M_S,
        MAX_VELOCITY_SCALE_M_S,
        "m/s",
    )?;
    above(
        &key("collision_radius_m"),
        e.collision_radius_m,
        0.0,
        MAX_COLLISION_RADIUS_M,
        "m",
    )?;
    // The drones start apart: a separation within the collision radius collides at once.
    above(
        &key("separation_m"),
        e.separation_m,
        e.collision_radius_m,
        MAX_SEPARATION_M,
        "m (collision_radius_m)",
    )?;
    // The floor is below the start: an agent starting on or below it has touched it.
    between(&key("floor_m"), e.floor_m, 0.0, MAX_ALTITUDE_M, "m")?;
    above(
        &key("altitude_m"),
        e.altitude_m,
        e.floor_m,
        MAX_ALTITUDE_M,
        "m (floor_m)",
    )?;
    between(&key("step_s"), e.step_s, MIN_STEP_S, MAX_STEP_S, "s")?;
    // At least one agent step per episode.
    between(
        &key("time_limit_s"),
        e.time_limit_s,
        e.step_s,
        MAX_TIME_LIMIT_S,
        "s (step_s)",
    )?;
    between(
        &key("terminal_reward"),
        e.terminal_reward,
        0.0,
        MAX_TERMINAL_REWARD,
        "",
    )?;
    // Episodes end only when checked, once an agent step: the drones close in at twice the
    // speed, so a step longer than the collision radius takes them through each other unseen.
    let per_step = e.speed_m_s * e.step_s;
    if per_step > e.collision_radius_m {
        return Err(format!(
            "key '{}': {} m/s × step_s {} s = {} m flown per agent step must be at most \
             collision_radius_m {} m, or the drones pass through each other between two checks",
            key("speed_m_s"),
            shown(e.speed_m_s),
            shown(e.step_s),
            shown(per_step),
            shown(e.collision_radius_m)
        ));
    }
    Ok(())
}

/// Checks the environment's episode count (key `episodes`).
pub fn episodes(n: u64) -> Result<u64, String> {
    if (1..=MAX_EPISODES).contains(&n) {
        Ok(n)
    } else {
        Err(format!(
            "key 'episodes': must be between 1 and {MAX_EPISODES}, got {n}"
        ))
    }
}

/// Checks the encounter's frame in the world (key `frame.origin`).
pub fn frame(f: &Frame) -> Result<(), String> {
    for (i, v) in f.origin.iter().enumerate() {
        between(
            &format!("frame.origin[{i}]"),
            *v,
            -MAX_ORIGIN_M,
            MAX_ORIGIN_M,
            "m",
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The encounter's params under mutation fuzzing (`caravan_report::fuzz`: numbers
    /// replaced by 0, −1, 1e308, huge integers…, lines deleted or swapped): each input is
    /// refused with an error or accepted, never a panic, and an accepted one keeps its
    /// promise (a step never carries a drone past the collision radius). `PROPTEST_CASES`
    /// sets the number of inputs (2,000 in CI).
    #[test]
    fn fuzz_encounter_params_never_panic() {
        let text = serde_json::to_string_pretty(&Encounter::default()).unwrap();
        let cases: u64 = std::env::var("PROPTEST_CASES")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(2_000);
        for seed in 0..cases {
            let mutated = caravan_report::fuzz::mutate(&text, seed);
            let Ok(e) = serde_json::from_str::<Encounter>(&mutated) else {
                continue;
            };
            if encounter(&e).is_ok() {
                assert!(e.speed_m_s * e.step_s <= e.collision_radius_m, "{mutated}");
            }
        }
    }

    #[test]
    fn the_default_encounter_and_frame_are_in_range() {
        encounter(&Encounter::default()).unwrap();
        frame(&Frame::default()).unwrap();
        assert_eq!(episodes(20), Ok(20));
        assert_eq!(episodes(100_000), Ok(100_000));
    }

    #[test]
    fn out_of_range_numbers_name_their_key() {
        let bad = |f: fn(&mut Encounter)| {
            let mut e = Encounter::default();
            f(&mut e);
            encounter(&e).unwrap_err()
        };
        assert_eq!(
            bad(|e| e.speed_m_s = 1e308),
            "key 'encounter.speed_m_s': must be above 0 and at most 40 m/s, got 1e308"
        );
        assert_eq!(
            bad(|e| e.speed_m_s = f64::NAN),
            "key 'encounter.speed_m_s': must be above 0 and at most 40 m/s, got NaN"
        );
        assert!(bad(|e| e.speed_m_s = -1.0).starts_with("key 'encounter.speed_m_s'"));
        assert!(bad(|e| e.dv_m_s = 2.0).starts_with("key 'encounter.dv_m_s'"));
        assert!(bad(|e| e.separation_m = 0.4).starts_with("key 'encounter.separation_m'"));
        assert!(bad(|e| e.altitude_m = 0.05).starts_with("key 'encounter.altitude_m'"));
        assert!(bad(|e| e.altitude_m = 1e4).starts_with("key 'encounter.altitude_m'"));
        assert!(bad(|e| e.floor_m = -0.1).starts_with("key 'encounter.floor_m'"));
        assert!(bad(|e| e.step_s = 1e-300).starts_with("key 'encounter.step_s'"));
        assert!(bad(|e| e.time_limit_s = 0.01).starts_with("key 'encounter.time_limit_s'"));
        assert!(bad(|e| e.terminal_reward = -1.0).starts_with("key 'encounter.terminal_reward'"));
        assert!(
            bad(|e| e.velocity_scale_m_s = f64::INFINITY)
                .starts_with("key 'encounter.velocity_scale_m_s'")
        );
        assert!(
            bad(|e| e.collision_radius_m = 0.0).starts_with("key 'encounter.collision_radius_m'")
        );
        assert!(bad(|e| e.v_max_m_s = 41.0).starts_with("key 'encounter.v_max_m_s'"));
    }

    #[test]
    fn a_drone_may_not_fly_through_the_other_between_two_checks() {
        // 20 m/s at 1/24 s: 0.83 m a step, beyond the 0.5 m radius.
        let e = Encounter {
            speed_m_s: 20.0,
            ..Encounter::default()
        };
        let err = encounter(&e).unwrap_err();
        assert!(
            err.starts_with("key 'encounter.speed_m_s': 20 m/s × step_s"),
            "{err}"
        );
        let e = Encounter {
            speed_m_s: 10.0,
            ..Encounter::default()
        };
        encounter(&e).unwrap();
    }

    #[test]
    fn episodes_and_the_frame_have_bounds() {
        assert_eq!(
            episodes(0).unwrap_err(),
            "key 'episodes': must be between 1 and 1000000, got 0"
        );
        assert!(episodes(MAX_EPISODES + 1).is_err());
        let f = Frame {
            origin: [2.0, 1e308],
        };
        assert_eq!(
            frame(&f).unwrap_err(),
            "key 'frame.origin[1]': must be between -10000 and 10000 m, got 1e308"
        );
    }
}
