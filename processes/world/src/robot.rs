//! The differential-drive view of a robot description (see [`crate::description`]): a chassis
//! (root link with a box), two driven wheels on continuous joints (cylinders), and a caster
//! (a sphere on a fixed joint). Sensors, planners and agents of wheeled robots read this.

use crate::description::{Geometry, JointKind, Link, RobotDescription, load_description};
use std::path::Path;

#[derive(Debug, thiserror::Error)]
#[error("{file}: {message}")]
pub struct RobotError {
    pub file: String,
    pub message: String,
}

/// Mass properties and collision shape of one link, in its parent's (base_link) frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Body {
    pub mass: f64,
    /// Principal moments (ixx, iyy, izz), kg·m².
    pub inertia: [f64; 3],
    /// Position of the body's origin relative to base_link, m.
    pub position: [f64; 3],
}

#[derive(Debug, Clone, PartialEq)]
pub struct RobotModel {
    pub name: String,
    pub chassis: Body,
    /// Half extents of the chassis box and its centre relative to base_link.
    pub chassis_half_extents: [f64; 3],
    pub chassis_center: [f64; 3],
    /// Left then right; positions are the joint origins.
    pub wheels: [Body; 2],
    pub wheel_radius: f64,
    pub wheel_width: f64,
    pub caster: Body,
    pub caster_radius: f64,
}

impl RobotModel {
    /// Distance between the two wheels' contact points, m.
    pub fn wheel_separation(&self) -> f64 {
        self.wheels[0].position[1] - self.wheels[1].position[1]
    }

    /// Total mass, kg.
    pub fn mass(&self) -> f64 {
        self.chassis.mass + self.wheels[0].mass + self.wheels[1].mass + self.caster.mass
    }

    /// Height of base_link above the floor when the robot stands on its wheels, m.
    pub fn base_height(&self) -> f64 {
        self.wheel_radius - self.wheels[0].position[2]
    }
}

/// Reads a robot description and checks it has what the convoy robot needs.
pub fn load_robot(path: &Path) -> Result<RobotModel, RobotError> {
    let d = load_description(path).map_err(|e| RobotError {
        file: e.file,
        message: match e.line {
            Some(line) => format!("line {line}: {}", e.message),
            None => e.message,
        },
    })?;
    RobotModel::from_description(&d).map_err(|message| RobotError {
        file: d.file.clone(),
        message,
    })
}

fn body(link: &Link, position: [f64; 3]) -> Result<Body, String> {
    let i = link.inertial.as_ref().ok_or(format!(
        "link '{}' needs an <inertial> with a positive mass",
        link.name
    ))?;
    let inertia = [i.inertia[(0, 0)], i.inertia[(1, 1)], i.inertia[(2, 2)]];
    Ok(Body {
        mass: i.mass,
        inertia,
        position,
    })
}

fn xyz(p: &nalgebra::Isometry3<f64>) -> [f64; 3] {
    p.translation.vector.into()
}

/// Rotations and offsets below these count as none: a URDF's `1.5707963` for π/2 is 3e-8
/// away, and coordinates are written to a micrometre.
const ANGLE_TOLERANCE_RAD: f64 = 1e-6;
const OFFSET_TOLERANCE_M: f64 = 1e-9;

/// `what`'s `<origin rpy>` must be zero: the wheeled model keeps no rotation there.
fn unrotated(what: &str, origin: &nalgebra::Isometry3<f64>) -> Result<(), String> {
    if origin.rotation.angle() > ANGLE_TOLERANCE_RAD {
        let (r, p, y) = origin.rotation.euler_angles();
        return Err(format!(
            "{what}: <origin rpy=\"{r} {p} {y}\"> is turned; the wheeled model takes it aligned \
             with base_link (rpy=\"0 0 0\"); describe the robot as an articulated one to keep the rotation"
        ));
    }
    Ok(())
}

/// `what`'s `<origin xyz>` must be zero: the wheeled model places it at its joint.
fn unshifted(what: &str, origin: &nalgebra::Isometry3<f64>) -> Result<(), String> {
    if origin.translation.vector.norm() > OFFSET_TOLERANCE_M {
        let [x, y, z] = xyz(origin);
        return Err(format!(
            "{what}: <origin xyz=\"{x} {y} {z}\"> is off its joint; the wheeled model centres it on \
             the joint (xyz=\"0 0 0\")"
        ));
    }
    Ok(())
}

/// Whether `v` lies along ±y within the angle tolerance.
fn along_y(v: &nalgebra::Vector3<f64>) -> bool {
    let n = v.norm();
    n > 0.0 && (v.y.abs() / n) >= ANGLE_TOLERANCE_RAD.cos()
}

impl RobotModel {
    /// The differential-drive view of a robot description: a root link with a box, two
    /// continuous joints carrying cylinders (the wheels), a sphere on a fixed joint (the
    /// caster).
    pub fn from_description(d: &RobotDescription) -> Result<Self, String> {
        let root = &d.links[d.root];
        let (chassis_half_extents, chassis_center) = root
            .collisions
            .iter()
            .find_map(|c| match c.geometry {
                Geometry::Box { half_extents } => Some((half_extents, c)),
                _ => None,
            })
            .ok_or(format!(
                "root link '{}' needs a <box> collision shape (the chassis)",
                root.name
            ))
            .and_then(|(half_extents, c)| {
                let what = format!("root link '{}', the chassis <box> collision", root.name);
                unrotated(&what, &c.origin)?;
                Ok((half_extents, xyz(&c.origin)))
            })?;
        let chassis = body(root, [0.0; 3])?;

        let mut wheels = Vec::new();
        for j in d.joints.iter().filter(|j| j.kind == JointKind::Continuous) {
            let child = &d.links[j.child];
            let (radius, width, shape) = child
                .collisions
                .iter()
                .find_map(|c| match c.geometry {
                    Geometry::Cylinder { radius, length } => Some((radius, length, c)),
                    _ => None,
                })
                .ok_or(format!(
                    "wheel link '{}' (joint '{}') needs a <cylinder> collision shape",
                    child.name, j.name
                ))?;
            // The model spins each wheel about base_link's +y axis, its cylinder centred on the
            // joint: a description that says otherwise is refused, not reinterpreted. Rotations
            // are honoured where they keep that (a joint turned by rpy="-1.5708 0 0" with its
            // axis along z, as many ROS descriptions write it).
            let spin = j.origin.rotation * j.axis;
            if !along_y(&spin) || spin.y < 0.0 {
                return Err(format!(
                    "wheel joint '{}': its <axis> turned by its <origin rpy> points along ({:.3}, {:.3}, {:.3}) \
                     in base_link, not along +y; the wheeled model spins each wheel about base_link's +y axis",
                    j.name, spin.x, spin.y, spin.z
                ));
            }
            let what = format!("wheel link '{}', its <cylinder> collision", child.name);
            unshifted(&what, &shape.origin)?;
            if !along_y(&(j.origin.rotation * shape.origin.rotation * nalgebra::Vector3::z())) {
                return Err(format!(
                    "{what}: the cylinder stands along its frame's z axis, which the <origin rpy> of \
                     the collision and the joint must turn onto base_link's y axis (the axle), \
                     e.g. rpy=\"1.5707963 0 0\" on the collision"
                ));
            }
            wheels.push((body(child, xyz(&j.origin))?, radius, width));
        }
        if wheels.len() != 2 {
            return Err(format!(
                "expected exactly two continuous (wheel) joints, found {}",
                wheels.len()
            ));
        }
        wheels.sort_by(|a, b| b.0.position[1].total_cmp(&a.0.position[1]));
        let (right, left) = (wheels.pop().unwrap(), wheels.pop().unwrap());
        if left.0.position[1] <= 0.0 || right.0.position[1] >= 0.0 {
            return Err(
                "wheels must sit on either side of base_link (one at y > 0, one at y < 0)".into(),
            );
        }
        if (left.1 - right.1).abs() > 1e-9 {
            return Err(format!("wheel radii differ: {} and {}", left.1, right.1));
        }

        let sphere = |l: &Link| {
            l.collisions.iter().find_map(|c| match c.geometry {
                Geometry::Sphere { radius } => Some(radius),
                _ => None,
            })
        };
        let (caster_joint, caster_radius) = d
            .joints
            .iter()
            .filter(|j| j.kind == JointKind::Fixed)
            .find_map(|j| sphere(&d.links[j.child]).map(|r| (j, r)))
            .ok_or("no caster: expected a link with a <sphere> collision shape on a fixed joint")?;
        let caster = &d.links[caster_joint.child];
        if let Some(c) = caster
            .collisions
            .iter()
            .find(|c| matches!(c.geometry, Geometry::Sphere { .. }))
        {
            let what = format!("caster link '{}', its <sphere> collision", caster.name);
            unshifted(&what, &c.origin)?;
        }
        Ok(RobotModel {
            name: d.name.clone(),
            chassis,
            chassis_half_extents,
            chassis_center,
            wheel_radius: left.1,
            wheel_width: left.2,
            wheels: [left.0, right.0],
            caster: body(&d.links[caster_joint.child], xyz(&caster_joint.origin))?,
            caster_radius,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn convoy_bot() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch/convoy/robots/convoy_bot.urdf")
    }

    #[test]
    fn convoy_bot_has_the_reference_geometry() {
        let m = load_robot(&convoy_bot()).unwrap();
        assert!((m.wheel_radius - 0.067).abs() < 1e-12);
        assert!((m.wheel_separation() - 0.172).abs() < 1e-12);
        assert!((m.mass() - 1.5).abs() < 1e-9);
        assert!((m.base_height() - 0.067).abs() < 1e-12);
    }

    /// The convoy robot's description with `from` replaced by `to` (once).
    fn convoy_bot_with(from: &str, to: &str) -> Result<RobotModel, String> {
        let text = std::fs::read_to_string(convoy_bot()).unwrap();
        assert!(text.contains(from), "{from}");
        let d = crate::description::parse(&text.replacen(from, to, 1), "r.urdf", Path::new("."))
            .unwrap();
        RobotModel::from_description(&d)
    }

    #[test]
    fn a_wheel_joint_turned_the_ros_way_gives_the_same_robot() {
        // rpy -π/2 about x with the axis along z: the wheel still spins about +y.
        let left = r#"<origin xyz="0 0.086 0" rpy="0 0 0"/>
    <axis xyz="0 1 0"/>"#;
        let turned = convoy_bot_with(
            left,
            r#"<origin xyz="0 0.086 0" rpy="-1.5707963267948966 0 0"/>
    <axis xyz="0 0 1"/>"#,
        );
        // The cylinder, turned by the joint too, then stands along z: it must be turned back.
        let e = turned.unwrap_err();
        assert!(
            e.contains("left_wheel") && e.contains("onto base_link's y axis"),
            "{e}"
        );
        let text = std::fs::read_to_string(convoy_bot())
            .unwrap()
            .replacen(
                left,
                r#"<origin xyz="0 0.086 0" rpy="-1.5707963267948966 0 0"/>
    <axis xyz="0 0 1"/>"#,
                1,
            )
            .replacen(
                r#"<origin xyz="0 0 0" rpy="1.5707963 0 0"/>"#,
                "<origin/>",
                1,
            );
        let d = crate::description::parse(&text, "r.urdf", Path::new(".")).unwrap();
        let m = RobotModel::from_description(&d).unwrap();
        assert_eq!(m, load_robot(&convoy_bot()).unwrap());
    }

    #[test]
    fn rotations_the_wheeled_model_would_drop_are_refused() {
        for (from, to, expected) in [
            (
                r#"<origin xyz="-0.02 0 0.01" rpy="0 0 0"/>
      <geometry><box"#,
                r#"<origin xyz="-0.02 0 0.01" rpy="0 0 0.3"/>
      <geometry><box"#,
                "the chassis <box> collision: <origin rpy=",
            ),
            (
                r#"<axis xyz="0 1 0"/>"#,
                r#"<axis xyz="1 0 0"/>"#,
                "not along +y",
            ),
            (
                r#"<axis xyz="0 1 0"/>"#,
                r#"<axis xyz="0 -1 0"/>"#,
                "not along +y",
            ),
            (
                r#"<origin xyz="0 0 0" rpy="1.5707963 0 0"/>"#,
                r#"<origin xyz="0 0 0" rpy="0 0 0"/>"#,
                "onto base_link's y axis",
            ),
            (
                r#"<origin xyz="0 0 0" rpy="1.5707963 0 0"/>"#,
                r#"<origin xyz="0 0.01 0" rpy="1.5707963 0 0"/>"#,
                "is off its joint",
            ),
            (
                r#"<geometry><sphere radius="0.02"/></geometry>"#,
                r#"<origin xyz="0 0 -0.01"/><geometry><sphere radius="0.02"/></geometry>"#,
                "caster link 'caster'",
            ),
        ] {
            let e = convoy_bot_with(from, to).unwrap_err();
            assert!(e.contains(expected), "{to}: {e}");
        }
    }

    #[test]
    fn a_robot_without_wheels_is_rejected() {
        let text = std::fs::read_to_string(convoy_bot())
            .unwrap()
            .replace("continuous", "fixed");
        let d = crate::description::parse(&text, "r.urdf", Path::new(".")).unwrap();
        let e = RobotModel::from_description(&d).unwrap_err();
        assert!(e.contains("two continuous"), "{e}");
    }

    #[test]
    fn malformed_xml_is_a_clear_error() {
        let dir = std::env::temp_dir().join(format!("caravan-urdf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("bad.urdf");
        std::fs::write(&p, "<robot name='x'><link name='a'>").unwrap();
        let e = load_robot(&p).unwrap_err().to_string();
        assert!(
            e.contains("bad.urdf") && e.contains("not a valid URDF"),
            "{e}"
        );
    }
}
