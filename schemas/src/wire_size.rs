//! Bytes a message would take on a network, for the emulated links' bandwidth: a ROS message
//! sends only the items a sequence holds, where a Caravan message carries its containers at
//! full capacity (a scan sized for 1,081 beams, a map for a megabyte). So a message counts as
//! its size less the items its counted arrays (a `FixedVec`, a scan's `beam_count`, a map's
//! `width × height`) do not hold. Read from the type's layout, so a scenario's own types count
//! the same way as the catalog's.

use crate::describe::{Describe, Kind, Scalar, TypeLayout};

/// How to measure messages of one type; built once per topic from the type's layout.
#[derive(Debug, Clone, PartialEq)]
pub struct WireSize {
    /// The type's size, bytes.
    size: usize,
    /// Its top-level arrays with a count.
    counted: Vec<Counted>,
}

/// An array of which only a front part is valid.
#[derive(Debug, Clone, PartialEq)]
struct Counted {
    /// The fields whose product is the number of valid items: offset and kind.
    counts: Vec<(usize, Scalar)>,
    /// Items the array holds at most.
    capacity: usize,
    /// Bytes per item.
    stride: usize,
}

impl WireSize {
    /// The measure of messages laid out as `layout`. A count that names no integer field of
    /// the struct counts nothing, as the JSON view reads it.
    pub fn of_layout(layout: &TypeLayout) -> Self {
        let counted = layout
            .fields
            .iter()
            .filter(|f| !f.count.is_empty())
            .filter_map(|f| {
                let capacity = f.kind.array_len()?;
                let counts = f.count.iter().map(|name| {
                    let c = layout.fields.iter().find(|c| &c.name == name);
                    match c.map(|c| (c.offset, c.kind)) {
                        Some((offset, Kind::Scalar(s))) => (offset, s),
                        _ => (0, Scalar::F64),
                    }
                });
                Some(Counted {
                    counts: counts.collect(),
                    capacity,
                    stride: f.size / capacity.max(1),
                })
            });
        WireSize {
            size: layout.size,
            counted: counted.collect(),
        }
    }

    /// The measure of messages of type `T`.
    pub fn of<T: Describe>() -> Self {
        Self::of_layout(&T::layout())
    }

    /// The wire bytes of `message`, which must be of the type this measure was built for.
    pub fn measure<T: Describe>(&self, message: &T) -> usize {
        assert_eq!(
            size_of::<T>(),
            self.size,
            "a WireSize measures its own type"
        );
        let base = (message as *const T).cast::<u8>();
        let unheld: usize = self
            .counted
            .iter()
            .map(|a| {
                let held = a.counts.iter().fold(1u128, |n, &(offset, kind)| {
                    // SAFETY: a count is an integer field of `T` (the layout says where), so its
                    // bytes lie inside `message` and are initialised data, not padding.
                    let slot =
                        unsafe { core::slice::from_raw_parts(base.add(offset), kind.size()) };
                    n.saturating_mul(crate::view::count_value(kind, slot) as u128)
                });
                (a.capacity - held.min(a.capacity as u128) as usize) * a.stride
            })
            .sum();
        self.size - unheld
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{LaserScan, OccupancyGrid, Path2D, Pose2D};

    #[test]
    fn a_scan_counts_its_beams_twice_and_its_scalars_once() {
        let mut scan = LaserScan {
            beam_count: 360,
            ..LaserScan::default()
        };
        assert_eq!(WireSize::of::<LaserScan>().measure(&scan), 32 + 360 * 8);
        // A count past the capacity counts the capacity.
        scan.beam_count = u32::MAX;
        assert_eq!(
            WireSize::of::<LaserScan>().measure(&scan),
            size_of::<LaserScan>()
        );
    }

    #[test]
    fn a_map_counts_width_times_height_cells() {
        let mut map = crate::boxed_placement_new::<OccupancyGrid>();
        map.width = 20;
        map.height = 30;
        let empty = size_of::<OccupancyGrid>() - crate::MAP_MAX_CELLS;
        assert_eq!(WireSize::of::<OccupancyGrid>().measure(&*map), empty + 600);
    }

    #[test]
    fn a_vector_counts_its_length_and_the_items_it_holds() {
        let mut path = crate::boxed_placement_new::<Path2D>();
        let measure = WireSize::of::<Path2D>();
        assert_eq!(measure.measure(&*path), 8);
        path.poses.set_from_slice(&[Pose2D::default(); 3]);
        assert_eq!(measure.measure(&*path), 8 + 3 * size_of::<Pose2D>());
    }

    #[test]
    fn a_type_without_counts_is_its_size() {
        assert_eq!(WireSize::of::<Pose2D>().measure(&Pose2D::default()), 24);
    }
}
