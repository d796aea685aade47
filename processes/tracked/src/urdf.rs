//! The robot description (URDF) of a running-gear variant, generated from
//! [`crate::running_gear`]: a chassis box with a bevelled nose, two flippers on revolute joints about the front
//! main wheels' axes (0 in line with the main track, positive raises the tip, within
//! [`FLIPPER_RANGE_DEG`]; or fixed at an angle, for trying poses), and every wheel a link on
//! a continuous joint about y, its rim a cylinder and its teeth capsules.
//!
//! A flipper (a 0.3 kg arm carrying nine wheels) needs the physics' multibody joints: rapier's
//! impulse-joint solver diverged within 0.1 s. The physics holds it with a `servo` actuator
//! and the drive sends its angle (30° by default, [`FLIPPER_ANGLE_DEG`]).
//!
//! Every wheel joint has the reference's limits (effort 140 N·m, velocity 14 rad/s; the
//! launch files turn the wheels kinematically by default, as motors that never saturate, so
//! only the velocity limit binds); every wheel link its friction
//! (`<gazebo><mu1>100</mu1><mu2>50</mu2>`; Caravan's physics takes mu1 and the smaller of the
//! two surfaces' coefficients, as ODE does, so the terrain's friction decides the grip). The
//! robot weighs [`TOTAL_MASS_KG`] in every variant.

use crate::running_gear::{self, Carrier, Side, Variant, Wheel};
use std::fmt::Write;

/// The whole robot's mass, kg, the same for every variant (chosen; the reference gives the
/// wheels' only).
pub const TOTAL_MASS_KG: f64 = 20.0;
/// The chassis box, m: length, width, height (chosen: the main tracks' length, between them).
pub const CHASSIS_M: [f64; 3] = [0.44, 0.14, 0.10];
/// The chassis' bevelled nose, m: its belly starts to rise this far behind the front
/// (`[0]`) and meets the front face this high above the belly (`[1]`), a 31° glacis
/// (chosen: a tracked robot's hull is bevelled so that an obstacle between the tracks lifts
/// its nose; a square nose 4.3 cm above the ground stops on any 10 cm block between them).
pub const NOSE_M: [f64; 2] = [0.10, 0.06];
/// The chassis' centre of mass from the box's centre, m: 5 cm forward and 3 cm down (chosen:
/// the real robot carries its arm folded over the front and its batteries low in the hull).
/// With the mass in the middle no flipper motion gets the 20 cm step: the main track is too
/// short to carry the centre of mass over the edge before the robot rears past upright.
pub const CHASSIS_COM_M: [f64; 3] = [0.05, 0.0, -0.03];
/// Each flipper arm's mass, kg (chosen; the arm has no collider, its wheels touch).
pub const FLIPPER_MASS_KG: f64 = 0.3;
/// The reference's wheel joint limits for its big wheels: effort N·m, velocity rad/s. A
/// wheel of another radius gets the same rim force and rim speed (the track's motor drives
/// them all): effort × r/R, velocity × R/r.
pub const WHEEL_EFFORT_NM: f64 = 140.0;
pub const WHEEL_VELOCITY_RAD_S: f64 = 14.0;
/// The reference's anisotropic friction of the wheels (mu1 along, mu2 across).
pub const WHEEL_MU: [f64; 2] = [100.0, 50.0];
/// The flippers' resting angle above the main tracks' line, degrees: where the drive holds
/// them unless the operator asks otherwise (their tips up, off flat ground; chosen).
pub const FLIPPER_ANGLE_DEG: f64 = 30.0;
/// A movable flipper's range, degrees above the main tracks' line: from tip down (pushing the
/// body up) to upright (chosen).
pub const FLIPPER_RANGE_DEG: [f64; 2] = [-90.0, 90.0];
/// A movable flipper's largest torque, N·m (chosen: lifts the robot's front with room to
/// spare).
pub const FLIPPER_EFFORT_NM: f64 = 60.0;
/// A movable flipper's largest speed, rad/s (chosen: a quarter turn in 1.6 s).
pub const FLIPPER_VELOCITY_RAD_S: f64 = 1.0;

/// How the flippers are joined to the chassis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Flippers {
    /// Fixed at this angle above the main tracks' line, degrees.
    Fixed(f64),
    /// On revolute joints `left_flipper_joint` and `right_flipper_joint` about the front
    /// wheels' axis: position 0 in line with the main track, positive raises the tip, within
    /// [`FLIPPER_RANGE_DEG`].
    Movable,
}

/// Inertia of a solid box of `m` kg and full sizes `s`: (ixx, iyy, izz).
fn box_inertia(m: f64, s: [f64; 3]) -> [f64; 3] {
    let [x, y, z] = s.map(|v| v * v);
    [m * (y + z) / 12.0, m * (x + z) / 12.0, m * (x + y) / 12.0]
}

/// A box collider of the chassis: its centre (x, z), pitch about y (rad) and full size, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChassisBox {
    /// Centre in the chassis frame (x forward, z up), m.
    pub centre_xz: [f64; 2],
    /// URDF pitch about y, rad (positive turns x toward −z).
    pub pitch_rad: f64,
    /// Full length, width and height, m, each > 0.
    pub size: [f64; 3],
}

/// The chassis' colliders: the box [`CHASSIS_M`] with its lower front edge bevelled by
/// [`NOSE_M`], as three boxes (the part above the bevel's top, the part behind it, and a
/// box whose bottom face is the bevel), all within the chassis box.
pub fn chassis_boxes() -> [ChassisBox; 3] {
    let [l, w, h] = CHASSIS_M;
    let [run, rise] = NOSE_M;
    let (front, belly, top) = (l / 2.0, -h / 2.0, h / 2.0);
    let slope = rise.atan2(run);
    // Thick enough to close the bevel's corner, thin enough to stay under the chassis' top.
    let t = (run * rise / run.hypot(rise)).min((top - belly - rise) / slope.cos());
    let (mx, mz) = (front - run / 2.0, belly + rise / 2.0);
    [
        ChassisBox {
            centre_xz: [0.0, (belly + rise + top) / 2.0],
            pitch_rad: 0.0,
            size: [l, w, top - belly - rise],
        },
        ChassisBox {
            centre_xz: [-run / 2.0, belly + rise / 2.0],
            pitch_rad: 0.0,
            size: [l - run, w, rise],
        },
        ChassisBox {
            centre_xz: [mx - t / 2.0 * slope.sin(), mz + t / 2.0 * slope.cos()],
            // URDF pitch turns x toward −z: the box's x runs up the bevel.
            pitch_rad: -slope,
            size: [run.hypot(rise), w, t],
        },
    ]
}

fn inertial(out: &mut String, m: f64, i: [f64; 3], at: [f64; 3]) {
    let _ = writeln!(
        out,
        "    <inertial><origin xyz=\"{} {} {}\"/><mass value=\"{m}\"/><inertia ixx=\"{:.9}\" iyy=\"{:.9}\" izz=\"{:.9}\" \
         ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>",
        at[0], at[1], at[2], i[0], i[1], i[2]
    );
}

/// The `rpy` that lays a URDF cylinder's or capsule's axis (its z) along a wheel's axle (y).
const ALONG_AXLE_RPY: &str = "1.5707963267949 0 0";

/// One wheel's link: a cylinder about y (the rim) and, for a gear, a capsule per tooth.
fn wheel_link(out: &mut String, w: &Wheel) {
    let name = w.name();
    let _ = writeln!(out, "  <link name=\"{name}_wheel\">");
    let (m, r, h) = (running_gear::WHEEL_MASS_KG, w.radius_m, w.width_m);
    // Solid cylinder about y.
    let across = m * (3.0 * r * r + h * h) / 12.0;
    inertial(out, m, [across, m * r * r / 2.0, across], [0.0; 3]);
    let rim = w.radius_m - w.teeth.map_or(0.0, |t| t.depth_m);
    let _ = writeln!(
        out,
        "    <collision><origin rpy=\"{ALONG_AXLE_RPY}\"/><geometry><cylinder radius=\"{rim:.6}\" \
         length=\"{h}\"/></geometry></collision>"
    );
    if let Some(t) = w.teeth {
        // A tooth is a bar across the wheel's whole width, as a gear's teeth and a track's
        // grousers are: a capsule along the axis, its tip on the circumscribed radius, as
        // thick as half the tooth pitch at the rim. (Radial pins in the wheel's mid-plane
        // missed every edge met by the wheel's outer parts.) Rounded, so the contact normal
        // stays the ground's: box teeth flipped their normals to the teeth's sides.
        let radius = (std::f64::consts::TAU * rim / t.count as f64 / 4.0).min(h / 2.0);
        let centre = w.radius_m - radius;
        let length = (h - 2.0 * radius).max(1e-4);
        for k in 0..t.count {
            let a = t.phase_rad + std::f64::consts::TAU * k as f64 / t.count as f64;
            let _ = writeln!(
                out,
                "    <collision><origin xyz=\"{:.6} 0 {:.6}\" rpy=\"{ALONG_AXLE_RPY}\"/><geometry>\
                 <capsule radius=\"{radius:.6}\" length=\"{length:.6}\"/></geometry></collision>",
                centre * a.cos(),
                centre * a.sin(),
            );
        }
    }
    let _ = writeln!(out, "  </link>");
    let _ = writeln!(
        out,
        "  <gazebo reference=\"{name}_wheel\"><mu1>{}</mu1><mu2>{}</mu2></gazebo>",
        WHEEL_MU[0], WHEEL_MU[1]
    );
}

fn wheel_joint(out: &mut String, w: &Wheel) {
    let name = w.name();
    let scale = w.radius_m / running_gear::BIG_RADIUS_M;
    let (parent, y) = match w.carrier {
        Carrier::Chassis => (
            "base_link".to_string(),
            w.side.sign() * running_gear::MAIN_Y_M,
        ),
        Carrier::Flipper => (format!("{}_flipper", w.side.name()), 0.0),
    };
    let _ = writeln!(
        out,
        "  <joint name=\"{name}_joint\" type=\"continuous\"><parent link=\"{parent}\"/>\
         <child link=\"{name}_wheel\"/><origin xyz=\"{:.6} {y} {:.6}\"/><axis xyz=\"0 1 0\"/>\
         <limit effort=\"{:.6}\" velocity=\"{:.6}\"/></joint>",
        w.x_m,
        w.z_m,
        WHEEL_EFFORT_NM * scale,
        WHEEL_VELOCITY_RAD_S / scale
    );
}

/// The URDF text of `variant`, with movable flippers.
pub fn urdf(variant: Variant) -> String {
    urdf_with_flippers(variant, Flippers::Movable)
}

/// The URDF text of `variant` with the given flippers: fixed with their tips raised by an
/// angle above the main track's line (0 = in line, 90 = upright), or movable.
pub fn urdf_with_flippers(variant: Variant, flippers_joint: Flippers) -> String {
    let wheels = running_gear::wheels(variant);
    let flippers = 2.0 * FLIPPER_MASS_KG;
    let chassis_kg = TOTAL_MASS_KG - flippers - running_gear::WHEEL_MASS_KG * wheels.len() as f64;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "<?xml version=\"1.0\"?>\n<!-- Generated by caravan-tracked-urdf: the tracked robot, \
         running gear {} ({} wheels). Do not edit; regenerate. -->\n<robot name=\"tracked_{}\">",
        variant.name(),
        wheels.len(),
        variant.name()
    );
    let _ = writeln!(out, "  <link name=\"base_link\">");
    inertial(
        &mut out,
        chassis_kg,
        box_inertia(chassis_kg, CHASSIS_M),
        CHASSIS_COM_M,
    );
    for b in chassis_boxes() {
        let ([cx, cz], [x, y, z]) = (b.centre_xz, b.size);
        let _ = writeln!(
            out,
            "    <collision><origin xyz=\"{cx:.6} 0 {cz:.6}\" rpy=\"0 {:.9} 0\"/><geometry>\
             <box size=\"{x:.6} {y:.6} {z:.6}\"/></geometry></collision>",
            b.pitch_rad
        );
    }
    let _ = writeln!(out, "  </link>");
    let (px, pz) = running_gear::flipper_pivot();
    for side in Side::BOTH {
        let name = flipper_link(side);
        let _ = writeln!(out, "  <link name=\"{name}\">");
        inertial(
            &mut out,
            FLIPPER_MASS_KG,
            box_inertia(
                FLIPPER_MASS_KG,
                [running_gear::FLIPPER_LENGTH_M, 0.02, 0.04],
            ),
            [0.0; 3],
        );
        let _ = writeln!(out, "  </link>");
        let y = side.sign() * running_gear::FLIPPER_Y_M;
        // A rotation about y by −angle lifts the flipper's tip (x forward, z up).
        let _ = match flippers_joint {
            Flippers::Fixed(angle) => writeln!(
                out,
                "  <joint name=\"{name}_joint\" type=\"fixed\"><parent link=\"base_link\"/>\
                 <child link=\"{name}\"/><origin xyz=\"{px} {y} {pz}\" rpy=\"0 {:.9} 0\"/></joint>",
                -angle.to_radians()
            ),
            Flippers::Movable => writeln!(
                out,
                "  <joint name=\"{name}_joint\" type=\"revolute\"><parent link=\"base_link\"/>\
                 <child link=\"{name}\"/><origin xyz=\"{px} {y} {pz}\"/><axis xyz=\"0 -1 0\"/>\
                 <limit lower=\"{:.9}\" upper=\"{:.9}\" effort=\"{FLIPPER_EFFORT_NM}\" \
                 velocity=\"{FLIPPER_VELOCITY_RAD_S}\"/></joint>",
                FLIPPER_RANGE_DEG[0].to_radians(),
                FLIPPER_RANGE_DEG[1].to_radians()
            ),
        };
    }
    for w in &wheels {
        wheel_link(&mut out, w);
        wheel_joint(&mut out, w);
    }
    out.push_str("</robot>\n");
    out
}

/// A flipper's link name; its joint is this plus `_joint`.
fn flipper_link(side: Side) -> String {
    format!("{}_flipper", side.name())
}

/// The flippers' joint names, left first.
pub fn flipper_joints() -> Vec<String> {
    Side::BOTH
        .into_iter()
        .map(|s| format!("{}_joint", flipper_link(s)))
        .collect()
}

/// The name of every wheel joint of a side, in the order of [`running_gear::wheels`].
pub fn wheel_joints(variant: Variant, side: Side) -> Vec<String> {
    running_gear::wheels(variant)
        .iter()
        .filter(|w| w.side == side)
        .map(|w| format!("{}_joint", w.name()))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use caravan_world::description::{JointKind, RobotDescription};

    fn parse(v: Variant) -> RobotDescription {
        let file = format!("{}.urdf", v.name());
        caravan_world::description::parse(&urdf(v), &file, std::path::Path::new(".")).unwrap()
    }

    #[test]
    fn every_variant_loads_with_its_wheels_and_weighs_the_same() {
        for v in Variant::ALL {
            let d = parse(v);
            let wheels = running_gear::wheels(v).len();
            let continuous = d
                .joints
                .iter()
                .filter(|j| j.kind == JointKind::Continuous)
                .count();
            assert_eq!(continuous, wheels, "{v:?}");
            assert!(d.joints.len() <= 64, "{v:?}: a JointState holds 64");
            assert!(
                (d.mass() - TOTAL_MASS_KG).abs() < 1e-9,
                "{v:?}: {}",
                d.mass()
            );
        }
    }

    #[test]
    fn flippers_are_revolute_about_the_front_axis_and_the_mass_sits_forward_and_low() {
        let d = parse(Variant::V4);
        for side in ["left", "right"] {
            let j = &d.joints[d.joint(&format!("{side}_flipper_joint")).unwrap()];
            assert_eq!(j.kind, JointKind::Revolute);
            assert!((j.limits.lower - FLIPPER_RANGE_DEG[0].to_radians()).abs() < 1e-9);
            assert!((j.limits.upper - FLIPPER_RANGE_DEG[1].to_radians()).abs() < 1e-9);
            let (px, pz) = running_gear::flipper_pivot();
            let at = j.origin.translation.vector;
            assert!((at.x - px).abs() < 1e-12 && (at.z - pz).abs() < 1e-12);
        }
        let base = d.link("base_link").unwrap();
        let com = d.links[base]
            .inertial
            .as_ref()
            .unwrap()
            .origin
            .translation
            .vector;
        assert_eq!([com.x, com.y, com.z], CHASSIS_COM_M);
        // Fixed flippers, for trying poses, are not joints a drive can move.
        let fixed = urdf_with_flippers(Variant::V4, Flippers::Fixed(40.0));
        let d = caravan_world::description::parse(&fixed, "v4.urdf", std::path::Path::new("."))
            .unwrap();
        assert!(d.joints.iter().all(|j| j.kind != JointKind::Revolute));
    }

    /// Whether (x, z) in the chassis frame lies inside one of its boxes.
    fn in_chassis(x: f64, z: f64) -> bool {
        chassis_boxes().iter().any(|b| {
            let (dx, dz) = (x - b.centre_xz[0], z - b.centre_xz[1]);
            // Into the box's frame: undo URDF's pitch (x toward −z by pitch).
            let (c, s) = (b.pitch_rad.cos(), b.pitch_rad.sin());
            let (u, v) = (c * dx - s * dz, s * dx + c * dz);
            u.abs() <= b.size[0] / 2.0 + 1e-9 && v.abs() <= b.size[2] / 2.0 + 1e-9
        })
    }

    #[test]
    fn the_chassis_is_its_box_less_a_bevel_under_the_nose() {
        let [l, _, h] = CHASSIS_M;
        let [run, rise] = NOSE_M;
        let (front, belly) = (l / 2.0, -h / 2.0);
        // Every box stays within the chassis box.
        for b in chassis_boxes() {
            for (sx, sz) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
                let (hx, hz) = (sx * b.size[0] / 2.0, sz * b.size[2] / 2.0);
                let (c, s) = (b.pitch_rad.cos(), b.pitch_rad.sin());
                let (x, z) = (
                    b.centre_xz[0] + c * hx + s * hz,
                    b.centre_xz[1] - s * hx + c * hz,
                );
                assert!(
                    x.abs() <= front + 1e-9 && z.abs() <= h / 2.0 + 1e-9,
                    "{b:?}: {x} {z}"
                );
            }
        }
        // Solid on a grid of the box, except below the bevel's line.
        for i in 0..=44 {
            for k in 0..=10 {
                let (x, z) = (-front + i as f64 * l / 44.0, belly + k as f64 * h / 10.0);
                let above_bevel = z - belly >= (x - (front - run)) * rise / run - 1e-9;
                assert_eq!(in_chassis(x, z), above_bevel, "({x:.3}, {z:.3})");
            }
        }
        // The URDF carries the three boxes on the base.
        let d = parse(Variant::V4);
        assert_eq!(d.links[d.link("base_link").unwrap()].collisions.len(), 3);
    }

    #[test]
    fn gear_wheels_carry_one_collider_per_tooth_and_round_ones_a_rim_only() {
        let v4 = parse(Variant::V4);
        let wheel = v4.link("left_main_0_wheel").unwrap();
        assert_eq!(v4.links[wheel].collisions.len(), 1 + 12);
        let v3 = parse(Variant::V3);
        let wheel = v3.link("left_main_0_wheel").unwrap();
        assert_eq!(v3.links[wheel].collisions.len(), 1);
        assert_eq!(v3.links[wheel].friction, Some(100.0));
    }

    #[test]
    fn a_gears_teeth_are_bars_across_the_wheels_width() {
        // A grouser runs across the track: an edge met under a wheel's outer part must meet a
        // tooth too (radial pins in the mid-plane missed it; docs/tracked-passability.md, the teeth).
        for v in [Variant::V2, Variant::V4] {
            let d = parse(v);
            for w in running_gear::wheels(v) {
                let link = &d.links[d.link(&format!("{}_wheel", w.name())).unwrap()];
                for c in &link.collisions[1..] {
                    let caravan_world::description::Geometry::Capsule { radius, length } =
                        c.geometry
                    else {
                        panic!("{v:?} {}: a tooth that is not a capsule", w.name());
                    };
                    let axis = c.origin.rotation * nalgebra::Vector3::z();
                    assert!(axis.y.abs() > 1.0 - 1e-9, "{v:?} {}: {axis}", w.name());
                    assert!(c.origin.translation.vector.y.abs() < 1e-12);
                    assert!(
                        (length + 2.0 * radius - w.width_m).abs() < 1e-5,
                        "{v:?} {length} {radius} {}",
                        w.width_m
                    );
                }
            }
        }
    }

    #[test]
    fn a_gear_is_circumscribed_by_its_radius_and_small_wheels_keep_the_rim_limits() {
        for v in Variant::ALL {
            let d = parse(v);
            let w = d.link("left_main_0_wheel").unwrap();
            let r = crate::diff_drive::circumscribed_radius(&d.links[w]);
            let expected = running_gear::wheels(v)[0].radius_m;
            assert!((r - expected).abs() < 1e-6, "{v:?}: {r} vs {expected}");
            let j = &d.joints[d.joint("left_main_0_joint").unwrap()];
            let force = WHEEL_EFFORT_NM / running_gear::BIG_RADIUS_M;
            assert!(
                (j.limits.effort / r / force - 1.0).abs() < 1e-4,
                "{v:?}: {} {r}",
                j.limits.effort
            );
            let speed = WHEEL_VELOCITY_RAD_S * running_gear::BIG_RADIUS_M;
            assert!((j.limits.velocity * r / speed - 1.0).abs() < 1e-4, "{v:?}");
        }
    }

    #[test]
    fn each_side_lists_its_own_wheel_joints() {
        let left = wheel_joints(Variant::V4, Side::Left);
        assert_eq!(left.len(), 18);
        assert!(left.iter().all(|j| j.starts_with("left_")));
        assert_eq!(left[0], "left_main_0_joint");
    }

    #[test]
    fn the_shipped_descriptions_are_the_generators_output() {
        let dir =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../launch/tracked/robots");
        for v in Variant::ALL {
            let shipped = std::fs::read_to_string(dir.join(format!("{}.urdf", v.name()))).unwrap();
            assert!(
                shipped == urdf(v),
                "launch/tracked/robots/{}.urdf is stale: regenerate with \
                 `cargo run -p caravan-tracked --bin caravan-tracked-urdf`",
                v.name()
            );
        }
    }
}
