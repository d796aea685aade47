//! Any robot from its URDF: links with their inertials and collision shapes, and the joints
//! that connect them into one tree.
//!
//! [`load_description`] reads the file (urdf-rs), loads the meshes it names (STL or OBJ) and
//! checks everything the physics needs before a group starts: one root, no kinematic loops,
//! known joint types, ordered limits, non-negative masses, positive inertias where a link has
//! mass. Each error names the file, the line where the element starts, and the link or joint.
//! What depends on how the robot is simulated (a fixed or floating base, which links move)
//! is checked by the physics process against the same description.
//!
//! Frames are URDF's: a joint's `origin` places the child link frame in the parent link frame
//! at joint position zero; the axis is in the joint (= child) frame.

mod mesh;
mod source;

use nalgebra::{Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3};
use std::path::Path;

pub use mesh::TriMesh;

/// A robot description that failed to load or check; `Display` gives `file:line: message`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}{}: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct DescriptionError {
    pub file: String,
    /// 1-based line of the element at fault, when known.
    pub line: Option<usize>,
    pub message: String,
}

/// A robot: links and joints in file order, forming a tree from `root`.
#[derive(Debug, Clone)]
pub struct RobotDescription {
    /// The `<robot name>`.
    pub name: String,
    /// The file it came from, for messages.
    pub file: String,
    pub links: Vec<Link>,
    pub joints: Vec<Joint>,
    /// Index of the root link (the one that is no joint's child).
    pub root: usize,
}

/// Mass properties of a link, in its own frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Inertial {
    /// kg, > 0.
    pub mass: f64,
    /// Centre of mass and the frame of `inertia`, in the link frame.
    pub origin: Isometry3<f64>,
    /// Inertia tensor about the centre of mass, in the `origin` frame, kg·m².
    pub inertia: Matrix3<f64>,
}

/// A collision shape of a link.
#[derive(Debug, Clone, PartialEq)]
pub struct Collision {
    /// The shape's frame in the link frame.
    pub origin: Isometry3<f64>,
    pub geometry: Geometry,
}

/// URDF geometries, sizes in metres. Cylinders and capsules stand along their frame's z axis.
#[derive(Debug, Clone, PartialEq)]
pub enum Geometry {
    Box {
        half_extents: [f64; 3],
    },
    Cylinder {
        radius: f64,
        length: f64,
    },
    Capsule {
        radius: f64,
        length: f64,
    },
    Sphere {
        radius: f64,
    },
    /// A triangle mesh, already scaled, in the shape's frame.
    Mesh(TriMesh),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    pub name: String,
    /// `None` for a link without mass (no `<inertial>`, or a mass of 0): a frame, or a part
    /// whose mass its parent already carries.
    pub inertial: Option<Inertial>,
    pub collisions: Vec<Collision>,
    /// Friction coefficient of its surfaces, from `<gazebo reference="…"><mu1>`; `None`:
    /// the simulator's default.
    pub friction: Option<f64>,
    /// Line of `<link` in the file, for messages.
    pub line: Option<usize>,
}

/// Joint types the physics simulates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    Fixed,
    Revolute,
    Continuous,
    Prismatic,
}

impl JointKind {
    /// The URDF name.
    pub fn name(self) -> &'static str {
        match self {
            JointKind::Fixed => "fixed",
            JointKind::Revolute => "revolute",
            JointKind::Continuous => "continuous",
            JointKind::Prismatic => "prismatic",
        }
    }

    /// Whether the joint has a degree of freedom.
    pub fn is_movable(self) -> bool {
        self != JointKind::Fixed
    }
}

/// Bounds of a joint, from `<limit>`. Infinite where the file gives none.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Position bounds, rad or m; ±∞ for a continuous joint.
    pub lower: f64,
    pub upper: f64,
    /// Largest actuator effort, N·m or N; ∞ when the file gives 0 or none.
    pub effort: f64,
    /// Largest speed, rad/s or m/s; ∞ when the file gives 0 or none.
    pub velocity: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    pub name: String,
    pub kind: JointKind,
    /// Indices into [`RobotDescription::links`].
    pub parent: usize,
    pub child: usize,
    /// The child frame in the parent frame at joint position 0.
    pub origin: Isometry3<f64>,
    /// Unit axis in the child (joint) frame; unused for a fixed joint.
    pub axis: Vector3<f64>,
    pub limits: Limits,
    /// Viscous damping (N·m·s/rad or N·s/m) and dry friction (N·m or N) from `<dynamics>`.
    pub damping: f64,
    pub friction: f64,
    /// Line of `<joint` in the file, for messages.
    pub line: Option<usize>,
}

impl RobotDescription {
    /// The link named `name`.
    pub fn link(&self, name: &str) -> Option<usize> {
        self.links.iter().position(|l| l.name == name)
    }

    /// The joint named `name`.
    pub fn joint(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// The joint whose child is link `link`; `None` for the root.
    pub fn parent_joint(&self, link: usize) -> Option<usize> {
        self.joints.iter().position(|j| j.child == link)
    }

    /// Joints whose parent is link `link`, in file order.
    pub fn child_joints(&self, link: usize) -> impl Iterator<Item = usize> + '_ {
        (0..self.joints.len()).filter(move |&j| self.joints[j].parent == link)
    }

    /// Movable joints in file order: the robot's joint order on its topics.
    pub fn movable_joints(&self) -> Vec<usize> {
        (0..self.joints.len())
            .filter(|&j| self.joints[j].kind.is_movable())
            .collect()
    }

    /// Pose of every link frame relative to the root frame with all joints at 0.
    pub fn rest_poses(&self) -> Vec<Isometry3<f64>> {
        let mut poses = vec![Isometry3::identity(); self.links.len()];
        let mut stack = vec![self.root];
        while let Some(link) = stack.pop() {
            for j in self.child_joints(link) {
                let joint = &self.joints[j];
                poses[joint.child] = poses[link] * joint.origin;
                stack.push(joint.child);
            }
        }
        poses
    }

    /// Total mass, kg.
    pub fn mass(&self) -> f64 {
        self.links
            .iter()
            .filter_map(|l| l.inertial.as_ref().map(|i| i.mass))
            .sum()
    }

    /// An error about this file at `line`.
    pub fn error(&self, line: Option<usize>, message: String) -> DescriptionError {
        DescriptionError {
            file: self.file.clone(),
            line,
            message,
        }
    }
}

/// Reads a URDF file and the meshes it names, and checks the robot it describes.
pub fn load_description(path: &Path) -> Result<RobotDescription, DescriptionError> {
    let file = path.display().to_string();
    let text = caravan::input::read_to_string(path).map_err(|e| DescriptionError {
        file: file.clone(),
        line: None,
        message: format!("cannot read: {e}"),
    })?;
    parse(&text, &file, path.parent().unwrap_or(Path::new(".")))
}

/// Parses URDF `text` (from `file`; meshes relative to `dir`).
pub fn parse(text: &str, file: &str, dir: &Path) -> Result<RobotDescription, DescriptionError> {
    let err = |line: Option<usize>, message: String| DescriptionError {
        file: file.to_string(),
        line,
        message,
    };
    // urdf-rs reports an unknown joint type without naming the joint; check types first.
    for tag in source::elements(text, "joint") {
        let kind = tag.attribute("type").unwrap_or_default();
        if !["revolute", "continuous", "prismatic", "fixed"].contains(&kind.as_str()) {
            let name = tag.attribute("name").unwrap_or_default();
            let why = if ["floating", "planar", "spherical"].contains(&kind.as_str()) {
                "is not simulated"
            } else {
                "is not a URDF joint type"
            };
            return Err(err(
                Some(tag.line),
                format!(
                    "joint '{name}': type '{kind}' {why}; use revolute, continuous, prismatic \
                     or fixed (a free-flying robot is a floating base, chosen in the launch file)"
                ),
            ));
        }
    }
    let urdf = urdf_rs::read_from_string(text).map_err(|e| {
        let e = e.to_string();
        match source::missing_attribute(text, &e) {
            Some((line, what)) => err(Some(line), format!("{what} (not a valid URDF: {e})")),
            None => err(None, format!("not a valid URDF: {e}")),
        }
    })?;
    let line_of = |element: &str, name: &str| source::line_of(text, element, name);

    let mut links = Vec::with_capacity(urdf.links.len());
    for l in &urdf.links {
        let line = line_of("link", &l.name);
        if links.iter().any(|k: &Link| k.name == l.name) {
            return Err(err(line, format!("link '{}' is defined twice", l.name)));
        }
        let inertial = inertial(l).map_err(|m| err(line, format!("link '{}': {m}", l.name)))?;
        let mut collisions = Vec::new();
        for c in &l.collision {
            let geometry = geometry(&c.geometry, dir)
                .map_err(|m| err(line, format!("link '{}': collision {m}", l.name)))?;
            collisions.push(Collision {
                origin: isometry(&c.origin),
                geometry,
            });
        }
        links.push(Link {
            name: l.name.clone(),
            inertial,
            collisions,
            friction: None,
            line,
        });
    }
    for (line, link, value) in source::gazebo_mu1(text) {
        let l = links.iter_mut().find(|l| l.name == link).ok_or_else(|| {
            err(
                Some(line),
                format!("<gazebo reference=\"{link}\">: no link named '{link}'"),
            )
        })?;
        match value.parse::<f64>() {
            Ok(mu) if mu.is_finite() && mu >= 0.0 => l.friction = Some(mu),
            _ => {
                return Err(err(
                    Some(line),
                    format!(
                        "<gazebo reference=\"{link}\"><mu1>{value}</mu1>: a friction \
                         coefficient is a number ≥ 0"
                    ),
                ));
            }
        }
    }
    let index = |name: &str| links.iter().position(|l| l.name == name);

    let mut joints: Vec<Joint> = Vec::with_capacity(urdf.joints.len());
    for j in &urdf.joints {
        let line = line_of("joint", &j.name);
        let jerr = |m: String| err(line, format!("joint '{}': {m}", j.name));
        if joints.iter().any(|k| k.name == j.name) {
            return Err(jerr("defined twice".into()));
        }
        let parent = index(&j.parent.link)
            .ok_or_else(|| jerr(format!("parent link '{}' does not exist", j.parent.link)))?;
        let child = index(&j.child.link)
            .ok_or_else(|| jerr(format!("child link '{}' does not exist", j.child.link)))?;
        if parent == child {
            return Err(jerr(format!("joins link '{}' to itself", j.child.link)));
        }
        if let Some(other) = joints.iter().find(|k| k.child == child) {
            return Err(jerr(format!(
                "link '{}' already hangs from joint '{}': a link has one parent joint, and a \
                 second one would close a kinematic loop",
                j.child.link, other.name
            )));
        }
        let kind = match j.joint_type {
            urdf_rs::JointType::Revolute => JointKind::Revolute,
            urdf_rs::JointType::Continuous => JointKind::Continuous,
            urdf_rs::JointType::Prismatic => JointKind::Prismatic,
            _ => JointKind::Fixed,
        };
        let axis = Vector3::from(j.axis.xyz.0);
        let norm = axis.norm();
        if kind.is_movable() && !(norm.is_finite() && norm > 1e-9) {
            return Err(jerr(format!("axis {:?} has no direction", j.axis.xyz.0)));
        }
        let limits = limits(kind, &j.limit).map_err(jerr)?;
        let (damping, friction) = j
            .dynamics
            .as_ref()
            .map_or((0.0, 0.0), |d| (d.damping, d.friction));
        if !(damping.is_finite() && damping >= 0.0 && friction.is_finite() && friction >= 0.0) {
            return Err(jerr(format!(
                "<dynamics damping=\"{damping}\" friction=\"{friction}\">: both must be zero \
                 or positive"
            )));
        }
        check_origin(&j.origin).map_err(jerr)?;
        joints.push(Joint {
            name: j.name.clone(),
            kind,
            parent,
            child,
            origin: isometry(&j.origin),
            axis: if kind.is_movable() {
                axis / norm
            } else {
                Vector3::z()
            },
            limits,
            damping,
            friction,
            line,
        });
    }

    let roots: Vec<usize> = (0..links.len())
        .filter(|&l| !joints.iter().any(|j| j.child == l))
        .collect();
    let root = match roots.as_slice() {
        [root] => *root,
        [] => {
            return Err(err(
                None,
                "every link is some joint's child, so the joints form a kinematic loop and \
                 there is no root link"
                    .into(),
            ));
        }
        [first, rest @ ..] => {
            let names: Vec<&str> = rest.iter().map(|&l| links[l].name.as_str()).collect();
            return Err(err(
                links[rest[0]].line,
                format!(
                    "links {names:?} are not connected to the root link '{}' by any joint \
                     (or the joints between them form a loop)",
                    links[*first].name
                ),
            ));
        }
    };
    let description = RobotDescription {
        name: urdf.name.clone(),
        file: file.to_string(),
        links,
        joints,
        root,
    };
    check_reachable(&description)?;
    Ok(description)
}

/// With one root and one parent per link, a link the root cannot reach sits on a loop.
fn check_reachable(d: &RobotDescription) -> Result<(), DescriptionError> {
    let mut seen = vec![false; d.links.len()];
    let mut stack = vec![d.root];
    while let Some(l) = stack.pop() {
        seen[l] = true;
        stack.extend(d.child_joints(l).map(|j| d.joints[j].child));
    }
    match seen.iter().position(|s| !s) {
        None => Ok(()),
        Some(l) => Err(d.error(
            d.links[l].line,
            format!(
                "link '{}' is on a kinematic loop: its joints lead back to itself, not to the \
                 root link '{}'",
                d.links[l].name, d.links[d.root].name
            ),
        )),
    }
}

/// An `<origin>` within a robot: offsets within ±100 m (one part's largest size), angles
/// within a thousand turns.
fn check_origin(p: &urdf_rs::Pose) -> Result<(), String> {
    use crate::limits::{MAX_ANGLE_RAD, MAX_PART_SIZE_M, coordinate};
    for (k, v) in p.xyz.0.iter().enumerate() {
        coordinate(&format!("<origin xyz>[{k}]"), *v, MAX_PART_SIZE_M)?;
    }
    for (k, v) in p.rpy.0.iter().enumerate() {
        coordinate(&format!("<origin rpy>[{k}]"), *v, MAX_ANGLE_RAD)?;
    }
    Ok(())
}

fn isometry(p: &urdf_rs::Pose) -> Isometry3<f64> {
    let [x, y, z] = p.xyz.0;
    let [r, pi, ya] = p.rpy.0;
    Isometry3::from_parts(
        Translation3::new(x, y, z),
        UnitQuaternion::from_euler_angles(r, pi, ya),
    )
}

fn inertial(l: &urdf_rs::Link) -> Result<Option<Inertial>, String> {
    let i = &l.inertial;
    let mass = i.mass.value;
    // A million kilograms is past any robot; beyond it the solver's numbers lose meaning.
    if !(0.0..=1e6).contains(&mass) {
        return Err(format!(
            "<mass value=\"{mass}\">: a mass must be 0 to 1e6 kg"
        ));
    }
    if mass == 0.0 {
        return Ok(None);
    }
    let t = &i.inertia;
    let inertia = Matrix3::new(
        t.ixx, t.ixy, t.ixz, t.ixy, t.iyy, t.iyz, t.ixz, t.iyz, t.izz,
    );
    let eig = inertia.symmetric_eigenvalues();
    let (a, b, c) = (eig[0], eig[1], eig[2]);
    let physical = eig.iter().all(|v| v.is_finite() && *v > 0.0)
        && a + b >= c * (1.0 - 1e-9)
        && b + c >= a * (1.0 - 1e-9)
        && a + c >= b * (1.0 - 1e-9);
    if !physical {
        return Err(format!(
            "<inertia ixx=\"{}\" iyy=\"{}\" izz=\"{}\" …> is not a rigid body's inertia: its \
             principal moments {:?} must be positive and each at most the sum of the other two",
            t.ixx,
            t.iyy,
            t.izz,
            [a, b, c]
        ));
    }
    Ok(Some(Inertial {
        mass,
        origin: isometry(&i.origin),
        inertia,
    }))
}

fn positive(what: &str, v: f64) -> Result<f64, String> {
    crate::limits::length(what, v, crate::limits::MAX_PART_SIZE_M)
}

fn geometry(g: &urdf_rs::Geometry, dir: &Path) -> Result<Geometry, String> {
    Ok(match g {
        urdf_rs::Geometry::Box { size } => {
            let [x, y, z] = size.0;
            for (axis, v) in [("x", x), ("y", y), ("z", z)] {
                positive(&format!("<box> size {axis}"), v)?;
            }
            Geometry::Box {
                half_extents: [x / 2.0, y / 2.0, z / 2.0],
            }
        }
        urdf_rs::Geometry::Cylinder { radius, length } => Geometry::Cylinder {
            radius: positive("<cylinder> radius", *radius)?,
            length: positive("<cylinder> length", *length)?,
        },
        urdf_rs::Geometry::Capsule { radius, length } => Geometry::Capsule {
            radius: positive("<capsule> radius", *radius)?,
            length: positive("<capsule> length", *length)?,
        },
        urdf_rs::Geometry::Sphere { radius } => Geometry::Sphere {
            radius: positive("<sphere> radius", *radius)?,
        },
        urdf_rs::Geometry::Mesh { filename, scale } => {
            let scale = scale.as_ref().map_or([1.0; 3], |s| s.0);
            Geometry::Mesh(mesh::load(filename, scale, dir)?)
        }
    })
}

fn limits(kind: JointKind, l: &urdf_rs::JointLimit) -> Result<Limits, String> {
    let bound = |v: f64| if v > 0.0 { v } else { f64::INFINITY };
    if l.effort.is_nan() || l.effort < 0.0 || l.velocity.is_nan() || l.velocity < 0.0 {
        return Err(format!(
            "<limit effort=\"{}\" velocity=\"{}\">: both must be zero (no bound) or positive",
            l.effort, l.velocity
        ));
    }
    let (lower, upper) = match kind {
        JointKind::Revolute | JointKind::Prismatic => {
            if l.lower.is_nan() || l.upper.is_nan() {
                return Err("<limit lower upper> must be numbers".into());
            }
            if l.lower > l.upper {
                return Err(format!(
                    "<limit lower=\"{}\" upper=\"{}\">: lower is above upper (reversed limits)",
                    l.lower, l.upper
                ));
            }
            if l.lower == l.upper {
                return Err(format!(
                    "<limit lower=\"{}\" upper=\"{}\">: a {} joint needs a range (lower < \
                     upper); a joint that cannot move is a fixed joint",
                    l.lower,
                    l.upper,
                    kind.name()
                ));
            }
            (l.lower, l.upper)
        }
        _ => (f64::NEG_INFINITY, f64::INFINITY),
    };
    Ok(Limits {
        lower,
        upper,
        effort: bound(l.effort),
        velocity: bound(l.velocity),
    })
}

#[cfg(test)]
mod tests;
