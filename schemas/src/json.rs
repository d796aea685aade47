//! JSON views of the fixed-capacity types: only the valid part of a container is written, so a
//! 682-beam scan records 682 ranges, not 1081.

use crate::{FixedString, FixedVec, LaserScan, OccupancyGrid};
use iceoryx2::prelude::{PlacementDefault, ZeroCopySend};
use serde::ser::{Serialize, SerializeStruct, Serializer};

/// `serialize_with` helper for arrays longer than serde's built-in 32.
pub(crate) fn slice<S: Serializer, T: Serialize, const N: usize>(
    v: &[T; N],
    s: S,
) -> Result<S::Ok, S::Error> {
    s.collect_seq(v.iter())
}

impl<const N: usize> Serialize for FixedString<N> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

impl<T: Copy + PlacementDefault + ZeroCopySend + Serialize, const N: usize> Serialize
    for FixedVec<T, N>
{
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.as_slice())
    }
}

impl Serialize for LaserScan {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let n = self.ranges().len();
        let mut st = s.serialize_struct("LaserScan", 9)?;
        st.serialize_field("angle_min", &self.angle_min)?;
        st.serialize_field("angle_max", &self.angle_max)?;
        st.serialize_field("angle_increment", &self.angle_increment)?;
        st.serialize_field("time_increment", &self.time_increment)?;
        st.serialize_field("scan_time", &self.scan_time)?;
        st.serialize_field("range_min", &self.range_min)?;
        st.serialize_field("range_max", &self.range_max)?;
        st.serialize_field("ranges", &self.ranges[..n])?;
        st.serialize_field("intensities", &self.intensities[..n])?;
        st.end()
    }
}

impl Serialize for OccupancyGrid {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut st = s.serialize_struct("OccupancyGrid", 5)?;
        st.serialize_field("resolution", &self.resolution)?;
        st.serialize_field("origin", &self.origin)?;
        st.serialize_field("width", &self.width)?;
        st.serialize_field("height", &self.height)?;
        st.serialize_field("data", self.cells())?;
        st.end()
    }
}
