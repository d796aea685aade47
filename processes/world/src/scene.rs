//! A world as solids for viewers ([`caravan::schemas::Scene`]): the floor, each wall, box and
//! cylinder extruded from the floor to its height, and a marker at every goal; and the robots'
//! bodies (chassis box and wheels from their description), posed on each robot.

use crate::world::{Shape as Section, World};
use caravan::schemas::{Pose3D, Quaternion, SCENE_MAX_SHAPES, Scene, Shape, Vector3};

/// Floor thickness drawn below z = 0, m.
const FLOOR_THICKNESS_M: f64 = 0.01;
/// Diameter of a goal marker, m.
const GOAL_MARKER_M: f64 = 0.15;
const FLOOR: [f32; 4] = [0.85, 0.85, 0.82, 1.0];
const WALL: [f32; 4] = [0.55, 0.55, 0.6, 1.0];
const OBSTACLE: [f32; 4] = [0.75, 0.55, 0.35, 1.0];
const GOAL: [f32; 4] = [0.2, 0.75, 0.3, 0.8];
const CHASSIS: [f32; 4] = [0.25, 0.45, 0.85, 1.0];
const WHEEL: [f32; 4] = [0.15, 0.15, 0.15, 1.0];

fn pose(x: f64, y: f64, z: f64, yaw: f64) -> Pose3D {
    Pose3D {
        position: Vector3 { x, y, z },
        orientation: Quaternion {
            x: 0.0,
            y: 0.0,
            z: (yaw / 2.0).sin(),
            w: (yaw / 2.0).cos(),
        },
    }
}

/// The world's solids, in the map frame; a world of more than [`SCENE_MAX_SHAPES`] solids
/// gives its first ones.
pub fn scene_of(world: &World) -> Box<Scene> {
    let mut shapes = vec![Shape {
        kind: Shape::BOX,
        pose: pose(
            world.size[0] / 2.0,
            world.size[1] / 2.0,
            -FLOOR_THICKNESS_M / 2.0,
            0.0,
        ),
        size: Vector3 {
            x: world.size[0],
            y: world.size[1],
            z: FLOOR_THICKNESS_M,
        },
        color: FLOOR,
        ..Default::default()
    }];
    for o in &world.obstacles {
        let (kind, x, y) = match o.shape {
            Section::Box { half_x, half_y } => (Shape::BOX, 2.0 * half_x, 2.0 * half_y),
            Section::Cylinder { radius } => (Shape::CYLINDER, 2.0 * radius, 2.0 * radius),
        };
        let color = match o.kind {
            crate::ObstacleKind::Wall => WALL,
            _ => OBSTACLE,
        };
        shapes.push(Shape {
            kind,
            pose: pose(o.center[0], o.center[1], o.height / 2.0, o.yaw),
            size: Vector3 { x, y, z: o.height },
            color,
            ..Default::default()
        });
    }
    for g in &world.goals {
        shapes.push(Shape {
            kind: Shape::SPHERE,
            pose: pose(g.at[0], g.at[1], GOAL_MARKER_M / 2.0, 0.0),
            size: Vector3 {
                x: GOAL_MARKER_M,
                y: GOAL_MARKER_M,
                z: GOAL_MARKER_M,
            },
            color: GOAL,
            ..Default::default()
        });
    }
    let mut scene = caravan::schemas::boxed_placement_new::<Scene>();
    for s in shapes.into_iter().take(SCENE_MAX_SHAPES) {
        // Cannot fail: at most SCENE_MAX_SHAPES are taken.
        let _ = scene.shapes.push(s);
    }
    scene
}

/// Adds the bodies of `count` robots described by `robot` to `scene`: each one's chassis box
/// and wheels, attached to it (see [`Shape::attached`]), as far as the scene has room.
pub fn add_robot_bodies(scene: &mut Scene, robot: &crate::RobotModel, count: usize) {
    let c = robot.chassis_center;
    let h = robot.chassis_half_extents;
    // A cylinder's axis is its z; a wheel's turns about the robot's y: a quarter turn about x.
    let wheel_axis = Quaternion {
        x: std::f64::consts::FRAC_1_SQRT_2,
        y: 0.0,
        z: 0.0,
        w: std::f64::consts::FRAC_1_SQRT_2,
    };
    for i in 0..count {
        let attached = i as u32 + 1;
        let chassis = Shape {
            kind: Shape::BOX,
            attached,
            pose: pose(c[0], c[1], c[2], 0.0),
            size: Vector3 {
                x: 2.0 * h[0],
                y: 2.0 * h[1],
                z: 2.0 * h[2],
            },
            color: CHASSIS,
        };
        let wheels = robot.wheels.iter().map(|w| Shape {
            kind: Shape::CYLINDER,
            attached,
            pose: Pose3D {
                orientation: wheel_axis,
                ..pose(w.position[0], w.position[1], w.position[2], 0.0)
            },
            size: Vector3 {
                x: 2.0 * robot.wheel_radius,
                y: 2.0 * robot.wheel_radius,
                z: robot.wheel_width,
            },
            color: WHEEL,
        });
        for shape in std::iter::once(chassis).chain(wheels) {
            if scene.shapes.push(shape).is_err() {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::parse_world;

    #[test]
    fn the_floor_each_obstacle_and_each_goal_become_solids() {
        let world = parse_world(
            r#"
[world]
name = "t"
size = [4.0, 3.0]
wall_height = 0.5

[[box]]
center = [1.0, 1.0]
size = [0.4, 0.2]
yaw = 1.5707963267948966

[[cylinder]]
center = [3.0, 2.0]
radius = 0.1
height = 0.3

[[goal]]
name = "a"
at = [2.0, 2.5]
"#,
        )
        .unwrap();
        let scene = scene_of(&world);
        let shapes = scene.shapes.as_slice();
        assert_eq!(shapes.len(), 4);
        assert_eq!(shapes[0].size.x, 4.0);
        assert_eq!(shapes[0].pose.position.y, 1.5);
        let b = shapes[1];
        assert_eq!(
            (b.kind, b.size.x, b.size.y, b.size.z),
            (Shape::BOX, 0.4, 0.2, 0.5)
        );
        assert_eq!(b.pose.position.z, 0.25);
        assert!((b.pose.orientation.z - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12);
        let c = shapes[2];
        assert_eq!((c.kind, c.size.x, c.size.z), (Shape::CYLINDER, 0.2, 0.3));
        assert_eq!(shapes[3].kind, Shape::SPHERE);
        assert_eq!(shapes[3].pose.position.x, 2.0);
    }

    #[test]
    fn each_robot_gets_its_chassis_and_wheels_attached_to_it() {
        let urdf = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../launch/convoy/robots/convoy_bot.urdf");
        let robot = crate::load_robot(&urdf).unwrap();
        let mut scene = caravan::schemas::boxed_placement_new::<Scene>();
        add_robot_bodies(&mut scene, &robot, 2);
        let shapes = scene.shapes.as_slice();
        let attached: Vec<u32> = shapes.iter().map(|s| s.attached).collect();
        assert_eq!(attached, [1, 1, 1, 2, 2, 2]);
        assert_eq!(shapes[0].size.x, 2.0 * robot.chassis_half_extents[0]);
        assert_eq!(shapes[1].kind, Shape::CYLINDER);
        assert_eq!(shapes[1].size.z, robot.wheel_width);
        assert_eq!(shapes[1].pose.position.y, robot.wheels[0].position[1]);
    }
}
