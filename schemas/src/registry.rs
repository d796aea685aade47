//! Every message type by its stable name, for tools that meet types at run time (recorder,
//! `caravan topic echo`, the Python generator). The types are listed once, in
//! [`message_types!`]; the catalog ([`crate::catalog`]) adds the structs they hold, the header
//! and the lockstep protocol.

/// Calls `$callback!` (given in brackets) with `$args` followed by every message type of Caravan's own (the
/// scenarios' types live in their crates): the one list of them.
#[doc(hidden)]
#[macro_export]
macro_rules! message_types {
    ([$($callback:tt)+] { $($args:tt)* }) => {
        $($callback)+!($($args)*
            Pose2D Pose3D Twist Vector3 Quaternion WheelSetpoint WheelState EncoderTicks Odometry
            LaserScan Imu OccupancyGrid Path2D Goal NodeStatus Collision JointState JointCommand
            LinkStates Contacts Wrench ForceTorques Scene Metrics RobotStates)
    };
}

/// Runs `$body` with `$T` bound to the message type named `$name`; `None` for an unknown name.
///
/// ```
/// let size = caravan_schemas::with_message_type!("caravan::Pose2D", |T| size_of::<T>());
/// assert_eq!(size, Some(24));
/// ```
#[macro_export]
macro_rules! with_message_type {
    ($name:expr, |$T:ident| $body:expr) => {
        $crate::message_types!([$crate::with_message_type] { @arms $name, $T, $body; })
    };
    (@arms $name:expr, $T:ident, $body:expr; $($ty:ident)*) => {{
        let name: &str = $name;
        $(
            if name == $crate::type_name::<$crate::$ty>() {
                #[allow(non_camel_case_types, dead_code)]
                type $T = $crate::$ty;
                Some($body)
            } else
        )* { None }
    }};
}

/// [`with_message_type!`], the lockstep protocol's own messages (`caravan::lockstep::Hello`,
/// `Grant`, `Done`), which cross between hosts like any topic, and the bench's blobs
/// ([`crate::bench`]), so that `caravan bench transport` can measure the bridge.
#[macro_export]
macro_rules! with_wire_type {
    ($name:expr, |$T:ident| $body:expr) => {{
        let name: &str = $name;
        $crate::with_message_type!(name, |$T| $body).or_else(|| {
            if name == $crate::type_name::<$crate::lockstep::Hello>() {
                type $T = $crate::lockstep::Hello;
                Some($body)
            } else if name == $crate::type_name::<$crate::lockstep::Grant>() {
                type $T = $crate::lockstep::Grant;
                Some($body)
            } else if name == $crate::type_name::<$crate::lockstep::Done>() {
                type $T = $crate::lockstep::Done;
                Some($body)
            } else {
                $crate::with_blob_type!(name, |$T| $body)
            }
        })
    }};
}

/// Names of all message types in the registry.
pub fn message_type_names() -> Vec<&'static str> {
    macro_rules! names {
        ($($ty:ident)*) => { vec![$(crate::type_name::<crate::$ty>()),*] };
    }
    crate::message_types!([names] {})
}
