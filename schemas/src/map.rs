use crate::describe::Describe;
use crate::{FixedVec, Pose2D};
use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};
use serde::Serialize;

/// Largest side of an [`OccupancyGrid`], in cells.
pub const MAP_MAX_SIDE: usize = 1024;
pub const MAP_MAX_CELLS: usize = MAP_MAX_SIDE * MAP_MAX_SIDE;
/// Largest number of poses in a [`Path2D`].
pub const PATH_MAX_POSES: usize = 1024;

/// An occupancy grid as nav_msgs/OccupancyGrid: −1 unknown, 0 free … 100 occupied.
/// Cells are row-major from `origin`, `width` cells per row.
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend, PlacementDefault, Describe)]
#[type_name("caravan::OccupancyGrid")]
pub struct OccupancyGrid {
    /// Metres per cell.
    pub resolution: f64,
    /// Pose of cell (0, 0)'s corner in the map frame.
    pub origin: Pose2D,
    pub width: u32,
    pub height: u32,
    #[count(width, height)]
    pub data: [i8; MAP_MAX_CELLS],
}

impl OccupancyGrid {
    /// The valid cells, `width × height` of them.
    pub fn cells(&self) -> &[i8] {
        let n = (self.width as usize * self.height as usize).min(MAP_MAX_CELLS);
        &self.data[..n]
    }

    /// Value at column `ix`, row `iy`, if inside the grid.
    pub fn get(&self, ix: u32, iy: u32) -> Option<i8> {
        (ix < self.width && iy < self.height)
            .then(|| self.data[iy as usize * self.width as usize + ix as usize])
    }
}

/// A planned path in the map frame.
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend, PlacementDefault, Serialize, Describe)]
#[type_name("caravan::Path2D")]
pub struct Path2D {
    pub poses: FixedVec<Pose2D, PATH_MAX_POSES>,
}

/// An operator goal: reach `pose` within `tolerance_m`.
#[repr(C)]
#[derive(
    Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault, Serialize, Describe,
)]
#[type_name("caravan::Goal")]
pub struct Goal {
    /// 0-based index in the goal sequence (A = 0, B = 1, …); equal to `total` once the last
    /// goal was reached.
    pub index: u32,
    /// Number of goals in the sequence.
    pub total: u32,
    pub pose: Pose2D,
    pub tolerance_m: f64,
}
