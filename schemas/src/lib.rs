//! Caravan message types and the typed topics that carry them.
//!
//! Every type is `#[repr(C)]`, fixed-capacity and pointer-free so that it can live in iceoryx2
//! shared memory and be read from C, C++ or Python with the same layout. Each carries a stable
//! type name (`caravan::<Name>`) that iceoryx2 uses to reject mismatched publishers and
//! subscribers. The stamped [`Header`] travels as iceoryx2's user header, beside the payload.

// The derive writes `::caravan_schemas::…` paths, which this crate's own types use too.
extern crate self as caravan_schemas;

mod articulated;
pub mod bench;
pub mod catalog;
pub mod describe;
pub mod descriptor;
mod fixed;
pub mod from_json;
mod geometry;
mod header;
mod json;
pub mod lockstep;
mod registry;
pub use registry::message_type_names;
mod map;
mod metrics;
pub mod reader;
mod robot;
mod scene;
mod sensors;
mod status;
mod topic;
pub mod topics;
mod view;
mod view_text;
pub mod wire;
pub mod wire_size;

pub use articulated::{
    Contact, Contacts, ForceTorque, ForceTorques, JointCommand, JointState, JointValue, LinkState,
    LinkStates, MAX_CONTACTS, MAX_FORCE_TORQUE, MAX_JOINTS, MAX_LINKS, NAME_BYTES, Name, Wrench,
};
pub use fixed::{FixedString, FixedVec};
pub use geometry::{Pose2D, Pose3D, Quaternion, Twist, Vector3, wrap_angle};
pub use header::Header;
pub use map::{Goal, MAP_MAX_CELLS, MAP_MAX_SIDE, OccupancyGrid, PATH_MAX_POSES, Path2D};
pub use metrics::{MAX_METRICS, Metrics, NamedValue, ShortName};
pub use robot::{
    Collision, EncoderTicks, MAX_ROBOT_STATES, Odometry, RobotState, RobotStates, WheelSetpoint,
    WheelState,
};
pub use scene::{SCENE_MAX_SHAPES, Scene, Shape};
pub use sensors::{Imu, LaserScan, SCAN_MAX_BEAMS};
pub use status::NodeStatus;
pub use topic::{Delivery, Topic};

/// A type that can travel on a Caravan topic.
///
/// Implemented for every schema type. `Copy` keeps them plain data; `Serialize` feeds
/// recordings and `caravan topic echo`; `PlacementDefault` lets a
/// publisher initialise a megabyte-sized message in shared memory without a stack copy;
/// `Describe` gives the layout that tools compiled without the type read it by.
pub trait Message:
    iceoryx2::prelude::ZeroCopySend
    + describe::Describe
    + serde::Serialize
    + iceoryx2::prelude::PlacementDefault
    + core::fmt::Debug
    + Copy
    + Send
    + 'static
{
}

impl<T> Message for T where
    T: iceoryx2::prelude::ZeroCopySend
        + describe::Describe
        + serde::Serialize
        + iceoryx2::prelude::PlacementDefault
        + core::fmt::Debug
        + Copy
        + Send
        + 'static
{
}

/// The stable cross-language type name of a message type.
pub fn type_name<T: Message>() -> &'static str {
    // SAFETY: `type_name` is `unsafe` only because implementors promise uniqueness; reading it
    // has no preconditions.
    unsafe { <T as iceoryx2::prelude::ZeroCopySend>::type_name() }
}

/// The stable cross-language type name of any type that can live in shared memory (the
/// lockstep protocol's messages and the header included).
pub fn type_name_of<T: iceoryx2::prelude::ZeroCopySend>() -> &'static str {
    // SAFETY: as in `type_name`.
    unsafe { <T as iceoryx2::prelude::ZeroCopySend>::type_name() }
}

/// The descriptor of `T` with its default value, as a tool compiled without `T` needs it.
pub fn descriptor_of<T: Message>() -> descriptor::Descriptor {
    let default = serde_json::to_value(boxed_placement_new::<T>().as_ref())
        .expect("a message's default serialises");
    descriptor::Descriptor::of::<T>().with_default(default)
}

/// A value initialised field by field with `PlacementDefault` (zeros, identity quaternions…).
pub fn placement_new<T: iceoryx2::prelude::PlacementDefault>() -> T {
    let mut value = core::mem::MaybeUninit::<T>::uninit();
    // SAFETY: `placement_default` initialises every field of the value it points to.
    unsafe {
        T::placement_default(value.as_mut_ptr());
        value.assume_init()
    }
}

/// Like [`placement_new`] but on the heap, for megabyte-sized messages such as a map.
pub fn boxed_placement_new<T: iceoryx2::prelude::PlacementDefault>() -> Box<T> {
    let mut value = Box::<T>::new_uninit();
    // SAFETY: as in `placement_new`.
    unsafe {
        T::placement_default(value.as_mut_ptr());
        value.assume_init()
    }
}

#[cfg(test)]
mod layout_tests;
