//! The simulation's state as topic messages, and commands from topics into the simulation:
//! joint states and commands, link states, contacts and wrenches. Joints and links travel by
//! their URDF names; `main.rs` only moves these messages.

use crate::actuator::Target;
use crate::simulation::Simulation;
use crate::wrench::WrenchCommand;
use caravan_schemas::{
    Contact, Contacts, ForceTorque, ForceTorques, JointCommand, JointState, JointValue, LinkState,
    LinkStates, MAX_CONTACTS, MAX_FORCE_TORQUE, MAX_JOINTS, MAX_LINKS, MAX_ROBOT_STATES,
    NAME_BYTES, Name, RobotState, RobotStates, Vector3, Wrench,
};
use caravan_world::description::RobotDescription;
use std::collections::HashSet;

/// Writes every robot's pose and velocity into `out` (`robots/state_true`), robot `i` at index
/// `i`; the caller sends it only for at most [`MAX_ROBOT_STATES`] robots.
pub fn robot_states(sim: &Simulation, out: &mut RobotStates) {
    out.robots.clear();
    for i in 0..sim.robot_count().min(MAX_ROBOT_STATES) {
        let state = RobotState {
            pose: sim.pose(i),
            twist: sim.twist(i),
        };
        // Cannot fail: at most MAX_ROBOT_STATES are pushed.
        let _ = out.robots.push(state);
    }
}

/// Checks that robot description `d`'s names and sizes fit the messages its robot would
/// publish; the error names the link or joint and its line.
pub fn check_fits(d: &RobotDescription, link_states: bool) -> Result<(), String> {
    let movable = d.movable_joints();
    if movable.len() > MAX_JOINTS {
        return Err(format!(
            "{}: {} movable joints; joint_states carries at most {MAX_JOINTS}",
            d.file,
            movable.len()
        ));
    }
    if link_states && d.links.len() > MAX_LINKS {
        return Err(format!(
            "{}: {} links; link_states carries at most {MAX_LINKS}",
            d.file,
            d.links.len()
        ));
    }
    let long = |name: &str| name.len() > NAME_BYTES;
    if let Some(j) = movable
        .iter()
        .map(|j| &d.joints[*j])
        .find(|j| long(&j.name))
    {
        return Err(d
            .error(
                j.line,
                format!(
                    "joint name '{}' is {} bytes; topics carry names of at most {NAME_BYTES}",
                    j.name,
                    j.name.len()
                ),
            )
            .to_string());
    }
    if let Some(l) = d.links.iter().find(|l| long(&l.name)) {
        return Err(d
            .error(
                l.line,
                format!(
                    "link name '{}' is {} bytes; topics carry names of at most {NAME_BYTES}",
                    l.name,
                    l.name.len()
                ),
            )
            .to_string());
    }
    Ok(())
}

/// Fills `out` with robot `i`'s joint readings.
pub fn joint_state(sim: &Simulation, i: usize, out: &mut JointState) {
    out.joints.clear();
    for (name, position, velocity, effort) in sim.joints(i) {
        let value = JointValue {
            name: Name::new(name),
            position,
            velocity,
            effort,
        };
        if out.joints.push(value).is_err() {
            break;
        }
    }
}

/// Fills `out` with the pose and velocity of robot `i`'s links.
pub fn link_states(sim: &Simulation, i: usize, out: &mut LinkStates) {
    let links = &sim.description(i).links;
    out.links.clear();
    for (link, (pose, twist)) in links.iter().zip(sim.link_states(i)) {
        if out
            .links
            .push(LinkState::new(&link.name, pose, twist))
            .is_err()
        {
            break;
        }
    }
}

/// Fills `out` with robot `i`'s contact points, the strongest first when there are more
/// than a message holds.
pub fn contacts(sim: &Simulation, i: usize, out: &mut Contacts) {
    let mut points = sim.contact_points(i);
    if points.len() > MAX_CONTACTS {
        points.sort_by(|a, b| b.normal_force.total_cmp(&a.normal_force));
    }
    let links = &sim.description(i).links;
    let v = |p: [f64; 3]| Vector3 {
        x: p[0],
        y: p[1],
        z: p[2],
    };
    out.contacts.clear();
    for p in points.iter().take(MAX_CONTACTS) {
        let other_link = match usize::try_from(p.other_robot) {
            Ok(r) => sim.description(r).links[p.other_link as usize]
                .name
                .as_str(),
            Err(_) => "",
        };
        let contact = Contact::new(
            &links[p.link].name,
            p.other_robot,
            other_link,
            v(p.point),
            v(p.normal),
            p.normal_force,
        );
        let _ = out.contacts.push(contact);
    }
}

/// Fills `out` with robot `i`'s force–torque sensor readings.
pub fn force_torque(sim: &Simulation, i: usize, out: &mut ForceTorques) {
    let v = |a: [f64; 3]| Vector3 {
        x: a[0],
        y: a[1],
        z: a[2],
    };
    out.sensors.clear();
    for (joint, force, torque) in sim.force_torque(i).into_iter().take(MAX_FORCE_TORQUE) {
        let reading = ForceTorque {
            joint: Name::new(joint),
            force: v(force),
            torque: v(torque),
        };
        let _ = out.sensors.push(reading);
    }
}

/// Turns joint commands into per-joint targets, warning once per unknown joint name.
#[derive(Debug, Default)]
pub struct CommandReader {
    warned: HashSet<String>,
}

impl CommandReader {
    /// Robot `i`'s targets in joint order from `cmd`: entries by name, or by index where the
    /// name is empty. Joints the command does not mention keep their targets (NaN).
    pub fn targets(&mut self, sim: &Simulation, i: usize, cmd: &JointCommand) -> Vec<Target> {
        let names: Vec<&str> = sim.joints(i).map(|(name, ..)| name).collect();
        let mut targets = vec![Target::default(); names.len()];
        for (k, value) in cmd.joints.as_slice().iter().enumerate() {
            let name = value.name.as_str();
            let index = if name.is_empty() {
                (k < names.len()).then_some(k)
            } else {
                names.iter().position(|n| *n == name)
            };
            let Some(index) = index else {
                let shown = if name.is_empty() {
                    format!("#{k}")
                } else {
                    name.into()
                };
                if self.warned.insert(format!("{i}/{shown}")) {
                    eprintln!(
                        "caravan-physics: robot/{i}/joint_command names joint {shown}, which \
                         robot {i} has not (movable joints: {}); ignored",
                        names.join(", ")
                    );
                }
                continue;
            };
            targets[index] = Target {
                position: value.position,
                velocity: value.velocity,
                effort: value.effort,
            };
        }
        targets
    }
}

/// The simulation's form of a wrench message.
pub fn wrench_command(w: &Wrench) -> Result<WrenchCommand, String> {
    let in_link_frame = match w.frame {
        Wrench::WORLD => false,
        Wrench::LINK => true,
        other => {
            return Err(format!(
                "frame {other} is neither {} (world) nor {} (link)",
                Wrench::WORLD,
                Wrench::LINK
            ));
        }
    };
    let a = |v: &Vector3| [v.x, v.y, v.z];
    Ok(WrenchCommand {
        link: w.link.as_str().to_string(),
        in_link_frame,
        point: a(&w.point),
        force: a(&w.force),
        torque: a(&w.torque),
        duration_s: w.duration_s,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use caravan_world::description::parse;
    use std::path::Path;

    fn arm(joint: &str) -> RobotDescription {
        let urdf = format!(
            r#"<robot name="r">
  <link name="base"/>
  <link name="arm"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="{joint}" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"#
        );
        parse(&urdf, "r.urdf", Path::new(".")).unwrap()
    }

    #[test]
    fn names_longer_than_a_message_holds_are_refused_with_their_line() {
        assert!(check_fits(&arm("shoulder"), true).is_ok());
        let long = "j".repeat(NAME_BYTES + 1);
        let e = check_fits(&arm(&long), false).unwrap_err();
        assert!(e.starts_with("r.urdf:4:") && e.contains("61 bytes"), "{e}");
    }

    #[test]
    fn wrench_frames_other_than_world_and_link_are_refused() {
        let mut w = Wrench {
            link: Name::new("arm"),
            frame: Wrench::LINK,
            ..Wrench::default()
        };
        assert!(wrench_command(&w).unwrap().in_link_frame);
        w.frame = 7;
        assert!(wrench_command(&w).unwrap_err().contains("frame 7"));
    }
}
