//! Robot descriptions from URDF: a chassis (root link with a box), two driven wheels on
//! continuous joints (cylinders), and a caster (a sphere on a fixed joint).

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
    let file = path.display().to_string();
    let err = |message: String| RobotError {
        file: file.clone(),
        message,
    };
    let text = std::fs::read_to_string(path).map_err(|e| err(format!("cannot read: {e}")))?;
    let urdf =
        urdf_rs::read_from_string(&text).map_err(|e| err(format!("not a valid URDF: {e}")))?;
    model(&urdf).map_err(err)
}

fn body(link: &urdf_rs::Link, position: [f64; 3]) -> Result<Body, String> {
    let i = &link.inertial;
    if i.mass.value <= 0.0 {
        return Err(format!(
            "link '{}' needs an <inertial> with a positive mass",
            link.name
        ));
    }
    let inertia = [i.inertia.ixx, i.inertia.iyy, i.inertia.izz];
    if inertia.iter().any(|&v| v <= 0.0) {
        return Err(format!(
            "link '{}' needs positive ixx, iyy and izz",
            link.name
        ));
    }
    Ok(Body {
        mass: i.mass.value,
        inertia,
        position,
    })
}

fn model(urdf: &urdf_rs::Robot) -> Result<RobotModel, String> {
    let link = |name: &str| {
        urdf.links
            .iter()
            .find(|l| l.name == name)
            .ok_or(format!("no link named '{name}'"))
    };
    let children: Vec<&str> = urdf.joints.iter().map(|j| j.child.link.as_str()).collect();
    let root = urdf
        .links
        .iter()
        .find(|l| !children.contains(&l.name.as_str()))
        .ok_or("no root link (every link is some joint's child)")?;
    let (chassis_half_extents, chassis_center) = root
        .collision
        .iter()
        .find_map(|c| match &c.geometry {
            urdf_rs::Geometry::Box { size } => {
                Some(([size[0] / 2.0, size[1] / 2.0, size[2] / 2.0], *c.origin.xyz))
            }
            _ => None,
        })
        .ok_or(format!(
            "root link '{}' needs a <box> collision shape (the chassis)",
            root.name
        ))?;
    let chassis = body(root, [0.0; 3])?;

    let mut wheels = Vec::new();
    for j in urdf
        .joints
        .iter()
        .filter(|j| matches!(j.joint_type, urdf_rs::JointType::Continuous))
    {
        let child = link(&j.child.link)?;
        let (radius, width) = child
            .collision
            .iter()
            .find_map(|c| match &c.geometry {
                urdf_rs::Geometry::Cylinder { radius, length } => Some((*radius, *length)),
                _ => None,
            })
            .ok_or(format!(
                "wheel link '{}' (joint '{}') needs a <cylinder> collision shape",
                child.name, j.name
            ))?;
        wheels.push((body(child, *j.origin.xyz)?, radius, width));
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

    let caster_joint = urdf
        .joints
        .iter()
        .find(|j| {
            matches!(j.joint_type, urdf_rs::JointType::Fixed)
                && link(&j.child.link).is_ok_and(|l| {
                    l.collision
                        .iter()
                        .any(|c| matches!(c.geometry, urdf_rs::Geometry::Sphere { .. }))
                })
        })
        .ok_or("no caster: expected a link with a <sphere> collision shape on a fixed joint")?;
    let caster_link = link(&caster_joint.child.link)?;
    let caster_radius = caster_link
        .collision
        .iter()
        .find_map(|c| match c.geometry {
            urdf_rs::Geometry::Sphere { radius } => Some(radius),
            _ => None,
        })
        .expect("checked above");
    Ok(RobotModel {
        name: urdf.name.clone(),
        chassis,
        chassis_half_extents,
        chassis_center,
        wheel_radius: left.1,
        wheel_width: left.2,
        wheels: [left.0, right.0],
        caster: body(caster_link, *caster_joint.origin.xyz)?,
        caster_radius,
    })
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

    #[test]
    fn a_robot_without_wheels_is_rejected() {
        let text = std::fs::read_to_string(convoy_bot())
            .unwrap()
            .replace("continuous", "fixed");
        let urdf = urdf_rs::read_from_string(&text).unwrap();
        let e = model(&urdf).unwrap_err();
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
