//! Collisions of robots with obstacles and with each other, as start/stop events.
//!
//! After every physics step the monitor reads rapier's contact graph for each robot's
//! colliders and forms the set of touching (robot, other) pairs, `other` being another robot's
//! index or −1 for the world (walls, boxes, cylinders, and the floor when the chassis itself
//! touches it, i.e. the robot tipped over). Wheels and caster on the floor are how a robot
//! stands, not collisions. Comparing the set with the previous one gives the events; a
//! contact between robots i and j yields one event for each of them.
//!
//! The contact graph is read rather than rapier's collision events because a robot is four
//! colliders: the monitor reports a robot-level contact once, however many of its colliders
//! touch, and sorted sets make the event order independent of rapier's internal order.

use crate::scene::{Part, Scene};
use caravan_schemas::Collision;
use std::collections::BTreeSet;

/// Two colliders closer than this count as touching, m. rapier keeps speculative contact
/// points up to its prediction distance (2 cm) apart; those are not collisions yet.
pub const TOUCH_DISTANCE: f32 = 0.002;

/// Remembers which pairs touch and reports changes.
#[derive(Debug, Default, Clone)]
pub struct ContactMonitor {
    touching: BTreeSet<(u32, i32)>,
}

impl ContactMonitor {
    /// Pairs touching now, sorted by robot then other.
    pub fn touching(&self) -> impl Iterator<Item = (u32, i32)> + '_ {
        self.touching.iter().copied()
    }

    /// Reads the scene's contacts and appends begun and ended contacts to `events`.
    pub fn update(&mut self, scene: &Scene, events: &mut Vec<Collision>) {
        let now = touching_pairs(scene);
        for &(robot, other) in self.touching.difference(&now) {
            events.push(event(robot, other, false));
        }
        for &(robot, other) in now.difference(&self.touching) {
            events.push(event(robot, other, true));
        }
        self.touching = now;
    }
}

fn event(robot: u32, other_robot: i32, started: bool) -> Collision {
    Collision {
        robot,
        other_robot,
        started: started as u32,
        _reserved: 0,
    }
}

fn touching_pairs(scene: &Scene) -> BTreeSet<(u32, i32)> {
    let colliders = &scene.physics.colliders;
    let narrow = &scene.physics.narrow_phase;
    let mut pairs = BTreeSet::new();
    for (i, robot) in scene.robots.iter().enumerate() {
        for &handle in &robot.colliders {
            let mine = Part::decode(colliders[handle].user_data);
            for pair in narrow.contact_pairs_with(handle) {
                let other = if pair.collider1 == handle {
                    pair.collider2
                } else {
                    pair.collider1
                };
                let Some(other_collider) = colliders.get(other) else {
                    continue;
                };
                let theirs = Part::decode(other_collider.user_data);
                let other_index = match theirs {
                    Part::Floor if !matches!(mine, Part::Chassis(_)) => continue,
                    Part::Floor | Part::Obstacle(_) => -1,
                    _ => match theirs.robot() {
                        Some(j) if j == i => continue,
                        Some(j) => j as i32,
                        None => -1,
                    },
                };
                let close = pair
                    .manifolds()
                    .iter()
                    .any(|m| m.points.iter().any(|p| p.dist <= TOUCH_DISTANCE));
                if close {
                    pairs.insert((i as u32, other_index));
                }
            }
        }
    }
    pairs
}
