//! Contacts: collision events between robots and with obstacles, and each robot's contact
//! points with their normal forces.
//!
//! After every physics step the monitor reads rapier's contact graph for each robot's
//! colliders and forms the set of touching (robot, other) pairs, `other` being another robot's
//! index or −1 for the world (walls, boxes, cylinders, and the floor when the root link itself
//! touches it, i.e. the robot tipped over). Wheels, casters and other links on the floor are
//! how a robot stands, not collisions. Comparing the set with the previous one gives the
//! events; a contact between robots i and j yields one event for each of them.
//!
//! The contact graph is read rather than rapier's collision events because a robot is many
//! colliders: the monitor reports a robot-level contact once, however many of its colliders
//! touch, and sorted sets make the event order independent of rapier's internal order.

use super::rapier::prelude::*;
use super::scene::{Part, Scene};
use crate::robot::ContactPoint;
use caravan_schemas::Collision;
use std::collections::BTreeSet;

/// Two colliders closer than this count as touching, m. rapier keeps speculative contact
/// points up to its prediction distance (2 cm) apart; those are not collisions yet.
pub const TOUCH_DISTANCE: Real = 0.002;

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

/// The other collider of a contact pair with `handle`.
fn other_of(pair: &ContactPair, handle: ColliderHandle) -> ColliderHandle {
    if pair.collider1 == handle {
        pair.collider2
    } else {
        pair.collider1
    }
}

fn touching_pairs(scene: &Scene) -> BTreeSet<(u32, i32)> {
    let colliders = &scene.physics.colliders;
    let narrow = &scene.physics.narrow_phase;
    let mut pairs = BTreeSet::new();
    for (i, robot) in scene.robots.iter().enumerate() {
        for &handle in &robot.colliders {
            let mine = Part::decode(colliders[handle].user_data);
            let is_root = matches!(mine, Part::Link { link, .. } if link == robot.root_link);
            for pair in narrow.contact_pairs_with(handle) {
                let Some(other_collider) = colliders.get(other_of(pair, handle)) else {
                    continue;
                };
                let theirs = Part::decode(other_collider.user_data);
                let other_index = match theirs {
                    Part::Floor if !is_root => continue,
                    Part::Floor | Part::Obstacle(_) => -1,
                    Part::Link { robot: j, .. } if j == i => continue,
                    Part::Link { robot: j, .. } => j as i32,
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

/// Robot `i`'s contact points after the last step (`dt` s long), wheels' tyres included.
pub fn points(scene: &Scene, i: usize, dt: f64) -> Vec<ContactPoint> {
    let colliders = &scene.physics.colliders;
    let narrow = &scene.physics.narrow_phase;
    let robot = &scene.robots[i];
    let mut out = Vec::new();
    for &handle in robot.colliders.iter().chain(&robot.tyres) {
        let Part::Link { link, .. } = Part::decode(colliders[handle].user_data) else {
            continue;
        };
        for pair in narrow.contact_pairs_with(handle) {
            let Some(other) = colliders.get(other_of(pair, handle)) else {
                continue;
            };
            let (other_robot, other_link) = match Part::decode(other.user_data) {
                Part::Link { robot, link } => (robot as i32, link as i32),
                _ => (-1, -1),
            };
            let mine_first = pair.collider1 == handle;
            let me = &colliders[handle];
            // The solver's manifolds hold the impulses: for a compound (a gear's rim and
            // teeth) rapier solves clusters of its per-shape manifolds, whose own points
            // then carry none.
            for m in pair.solver_manifolds() {
                // rapier's normal points from collider 1 to collider 2.
                let sign: Real = if mine_first { -1.0 } else { 1.0 };
                let n = m.data.normal * sign;
                let shape = if mine_first {
                    m.subshape_pos1()
                } else {
                    m.subshape_pos2()
                };
                for p in &m.points {
                    if p.dist > TOUCH_DISTANCE {
                        continue;
                    }
                    // A point of a compound's part is in that part's frame.
                    let local = if mine_first { p.local_p1 } else { p.local_p2 };
                    let local = shape.map_or(local, |pos| pos.transform_point(local));
                    let at = me.position().transform_point(local);
                    out.push(ContactPoint {
                        link,
                        other_robot,
                        other_link,
                        point: [at.x as f64, at.y as f64, at.z as f64],
                        normal: [n.x as f64, n.y as f64, n.z as f64],
                        normal_force: p.data.impulse as f64 / dt,
                    });
                }
            }
        }
    }
    out
}
