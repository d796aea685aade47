//! What a world is made of, for viewers: solids posed in the map frame, and the robots'
//! bodies posed on the robots. The physics publishes
//! its world on [`crate::topics::scene`] (again every simulated second, so a late viewer gets
//! it), and the recorder and the live view turn it into Foxglove's `SceneUpdate`.

use crate::describe::Describe;
use crate::{FixedVec, Pose3D, Vector3};
use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};
use serde::Serialize;

/// Most solids in a [`Scene`]; a larger world sends its first ones.
pub const SCENE_MAX_SHAPES: usize = 2048;

/// One solid: a box, an upright cylinder (its axis along its own z) or a sphere.
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::Shape")]
pub struct Shape {
    /// [`Shape::BOX`], [`Shape::CYLINDER`] or [`Shape::SPHERE`].
    pub kind: u32,
    /// Where it is posed: 0 in the map frame; i + 1 on robot i, in the frame of its true
    /// pose (the shape moves with the robot).
    pub attached: u32,
    /// The solid's centre and orientation in its frame (m).
    pub pose: Pose3D,
    /// Extent along its own x, y and z, m (a cylinder's: diameter, diameter, height).
    pub size: Vector3,
    /// Red, green, blue and opacity, each 0–1.
    pub color: [f32; 4],
}

impl Shape {
    pub const BOX: u32 = 0;
    pub const CYLINDER: u32 = 1;
    pub const SPHERE: u32 = 2;
}

/// A world's solids (floor, walls, obstacles, goal markers) and its robots' bodies.
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend, PlacementDefault, Serialize, Describe)]
#[type_name("caravan::Scene")]
pub struct Scene {
    pub shapes: FixedVec<Shape, SCENE_MAX_SHAPES>,
}
