//! From URDF geometry and inertials (f64, nalgebra) to rapier shapes, poses and mass
//! properties.
//!
//! URDF cylinders stand along their frame's z axis, rapier's along y. A cylinder is
//! symmetric about its axis and its mid-plane, so only the axis direction matters; an axis
//! within 1 µrad of a body axis is snapped onto it (a URDF's `rpy="1.5707963 0 0"` is a
//! quarter turn to 7 digits), which keeps the colliders of the usual wheel exactly aligned.

use super::rapier::prelude::*;
use caravan_world::description::{Collision, Geometry, Inertial};
use nalgebra::{Isometry3, Matrix3, UnitQuaternion, Vector3};

/// Axes closer than this to a body axis are snapped onto it, rad.
const SNAP: f64 = 1e-6;

pub fn vector(v: &Vector3<f64>) -> Vector {
    Vector::new(v.x as Real, v.y as Real, v.z as Real)
}

pub fn rotation(q: &UnitQuaternion<f64>) -> Rotation {
    Rotation::from_xyzw(q.i as Real, q.j as Real, q.k as Real, q.w as Real)
}

pub fn pose(iso: &Isometry3<f64>) -> Pose {
    Pose::from_parts(vector(&iso.translation.vector), rotation(&iso.rotation))
}

/// The inverse of [`vector`]: rapier's vector in f64.
pub fn vector_f64(v: Vector) -> Vector3<f64> {
    Vector3::new(v.x as f64, v.y as f64, v.z as f64)
}

/// The inverse of [`pose`]: rapier's pose in f64.
pub fn isometry(p: &Pose) -> Isometry3<f64> {
    let q = p.rotation;
    Isometry3::from_parts(
        vector_f64(p.translation).into(),
        UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(
            q.w as f64, q.x as f64, q.y as f64, q.z as f64,
        )),
    )
}

/// The collider frame for `geometry` placed at `at` (body frame): `at` itself, except that a
/// cylinder's frame is turned so that rapier's y axis lies along the URDF's z axis.
pub fn collider_iso(geometry: &Geometry, at: &Isometry3<f64>) -> Isometry3<f64> {
    let Geometry::Cylinder { .. } = geometry else {
        return *at;
    };
    let axis = at.rotation * Vector3::z();
    let quarter = std::f64::consts::FRAC_PI_2;
    let snapped = [
        (Vector3::y(), UnitQuaternion::identity()),
        (
            Vector3::z(),
            UnitQuaternion::from_euler_angles(quarter, 0.0, 0.0),
        ),
        (
            Vector3::x(),
            UnitQuaternion::from_euler_angles(0.0, 0.0, -quarter),
        ),
    ]
    .into_iter()
    .find(|(a, _)| axis.cross(a).norm() < SNAP);
    let rotation = match snapped {
        Some((_, r)) => r,
        None => at.rotation * UnitQuaternion::from_euler_angles(quarter, 0.0, 0.0),
    };
    Isometry3::from_parts(at.translation, rotation)
}

/// The collider pose for `geometry` placed at `at`.
pub fn collider_pose(geometry: &Geometry, at: &Isometry3<f64>) -> Pose {
    pose(&collider_iso(geometry, at))
}

/// One compound shape of a link's collisions, in its body's frame (the link at `link_pose`),
/// when it has several and all are primitives; `None` otherwise (one collider each).
pub fn compound(
    collisions: &[Collision],
    link_pose: &Isometry3<f64>,
    fixed: bool,
) -> Option<SharedShape> {
    if collisions.len() < 2
        || collisions
            .iter()
            .any(|c| matches!(c.geometry, Geometry::Mesh(_)))
    {
        return None;
    }
    let parts = collisions
        .iter()
        .map(|c| {
            let at = link_pose * c.origin;
            Some((
                collider_pose(&c.geometry, &at),
                shape(&c.geometry, fixed).ok()?,
            ))
        })
        .collect::<Option<Vec<_>>>()?;
    Some(SharedShape::compound(parts))
}

/// The rapier shape. Meshes become their convex hull on moving bodies and a triangle mesh
/// on fixed ones (rapier does not simulate dynamic triangle meshes well).
pub fn shape(geometry: &Geometry, fixed: bool) -> Result<SharedShape, String> {
    Ok(match geometry {
        Geometry::Box {
            half_extents: [x, y, z],
        } => SharedShape::cuboid(*x as Real, *y as Real, *z as Real),
        Geometry::Sphere { radius } => SharedShape::ball(*radius as Real),
        Geometry::Cylinder { radius, length } => {
            SharedShape::cylinder((length / 2.0) as Real, *radius as Real)
        }
        Geometry::Capsule { radius, length } => {
            SharedShape::capsule_z((length / 2.0) as Real, *radius as Real)
        }
        Geometry::Mesh(mesh) => {
            let points: Vec<Vector> = mesh
                .vertices
                .iter()
                .map(|p| Vector::new(p[0] as Real, p[1] as Real, p[2] as Real))
                .collect();
            if fixed {
                SharedShape::trimesh(points, mesh.triangles.clone())
                    .map_err(|e| format!("mesh: not a usable triangle mesh ({e})"))?
            } else {
                SharedShape::convex_hull(&points)
                    .ok_or("mesh: its points span no volume, so it has no convex hull")?
            }
        }
    })
}

/// Lowest z of `geometry` placed at `at`, m.
pub fn lowest_point(geometry: &Geometry, at: &Isometry3<f64>) -> f64 {
    match shape(geometry, false) {
        Ok(s) => s.compute_aabb(&collider_pose(geometry, at)).mins.z as f64,
        Err(_) => at.translation.vector.z,
    }
}

/// `j·a·aᵀ` about unit axis `axis` (link frame), expressed in the inertial frame `origin`.
pub fn axis_inertia(origin: &Isometry3<f64>, axis: &Vector3<f64>, j: f64) -> Matrix3<f64> {
    let a = origin.rotation.inverse() * axis;
    a * a.transpose() * j
}

/// The link's mass properties in the frame of the collider at `collider` (body frame), the
/// link sitting at `link` (body frame).
pub fn mass_properties(
    i: &Inertial,
    collider: &Isometry3<f64>,
    link: &Isometry3<f64>,
) -> MassProperties {
    let relative = collider.inverse() * link * i.origin;
    let com = vector(&relative.translation.vector);
    let diagonal = i.inertia.off_diagonal_is_zero();
    let (moments, principal) = if diagonal {
        (i.inertia.diagonal(), UnitQuaternion::identity())
    } else {
        let eigen = i.inertia.symmetric_eigen();
        let mut vectors = eigen.eigenvectors;
        let mut values = eigen.eigenvalues;
        if vectors.determinant() < 0.0 {
            vectors.swap_columns(1, 2);
            values.swap_rows(1, 2);
        }
        let r = nalgebra::Rotation3::from_matrix_unchecked(vectors);
        (values, UnitQuaternion::from_rotation_matrix(&r))
    };
    let frame = relative.rotation * principal;
    let moments = vector(&moments);
    if frame == UnitQuaternion::identity() {
        MassProperties::new(com, i.mass as Real, moments)
    } else {
        MassProperties::with_principal_inertia_frame(com, i.mass as Real, moments, rotation(&frame))
    }
}

trait OffDiagonal {
    fn off_diagonal_is_zero(&self) -> bool;
}

impl OffDiagonal for Matrix3<f64> {
    fn off_diagonal_is_zero(&self) -> bool {
        (0..3).all(|r| (0..3).all(|c| r == c || self[(r, c)] == 0.0))
    }
}

/// The rapier joint for a URDF joint whose frame in the parent body is `frame`. Frames: the
/// joint's axis is the child frame's `axis`; at position 0 the child frame sits at `frame`.
pub fn joint(joint: &caravan_world::description::Joint, frame: &Isometry3<f64>) -> GenericJoint {
    use caravan_world::description::JointKind;
    let axis = vector(&joint.axis);
    let anchor = vector(&frame.translation.vector);
    let mut generic: GenericJoint = match joint.kind {
        JointKind::Prismatic => PrismaticJointBuilder::new(axis)
            .local_anchor1(anchor)
            .local_anchor2(Vector::ZERO)
            .contacts_enabled(false)
            .limits([joint.limits.lower as Real, joint.limits.upper as Real])
            .into(),
        JointKind::Revolute => RevoluteJointBuilder::new(axis)
            .local_anchor1(anchor)
            .local_anchor2(Vector::ZERO)
            .contacts_enabled(false)
            .limits([joint.limits.lower as Real, joint.limits.upper as Real])
            .into(),
        JointKind::Continuous => RevoluteJointBuilder::new(axis)
            .local_anchor1(anchor)
            .local_anchor2(Vector::ZERO)
            .contacts_enabled(false)
            .into(),
        JointKind::Fixed => FixedJointBuilder::new()
            .local_anchor1(anchor)
            .contacts_enabled(false)
            .into(),
    };
    // A rotated joint origin: the parent-side frame turns with it, so that position 0 is
    // the URDF's rest pose.
    if frame.rotation != UnitQuaternion::identity() {
        let mut f1 = generic.local_frame1;
        f1.rotation = rotation(&frame.rotation) * generic.local_frame2.rotation;
        generic.set_local_frame1(f1);
    }
    generic
}
