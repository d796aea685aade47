//! The catalog of the shared message types: every type that crosses a process boundary (the
//! registry's message types with the structs they hold, the [`Header`] and the lockstep
//! protocol's messages) with its layout, and the topics of [`crate::topics`] by the names other languages give them.
//! `caravan schemas --python` and `--layout` print it.

use crate::Header;
use crate::describe::{Describe, TypeLayout};
use crate::descriptor::{Descriptor, layout_json};
use crate::lockstep::{Done, Grant, Hello};

/// Every described type, each after the types it contains: the header, the message types
/// ([`crate::message_types!`]) with the structs they hold, and the lockstep protocol's messages.
pub fn layouts() -> Vec<TypeLayout> {
    macro_rules! layouts {
        ($($ty:ident)*) => {{
            let mut all = vec![<Header as Describe>::layout()];
            $(all.extend(Descriptor::of::<crate::$ty>().layouts().iter().cloned());)*
            all.extend([Hello::layout(), Grant::layout(), Done::layout()]);
            all
        }};
    }
    let mut seen = std::collections::BTreeSet::new();
    let all: Vec<TypeLayout> = crate::message_types!([layouts] {});
    all.into_iter()
        .filter(|l| seen.insert(l.type_name))
        .collect()
}
/// Erases the message types of [`crate::topics`] helpers, keeping how they name topics, and
/// names each entry after its helper so that the table cannot drift from the functions.
macro_rules! topic_names {
    ($($constant:ident = $helper:ident),* $(,)?) => {
        &[$((stringify!($constant), || crate::topics::$helper().name().to_owned())),*]
    };
    ($($helper:ident),* $(,)?) => {
        &[$((stringify!($helper), |i| crate::topics::$helper(i).name().to_owned())),*]
    };
}

/// A global topic helper with its message type erased: the topic's name.
pub type GlobalTopic = fn() -> String;

/// The global topics of [`crate::topics`], by the constant names other languages give them.
pub const TOPIC_CONSTANTS: &[(&str, GlobalTopic)] = topic_names![
    STATUS = status,
    MAP = map,
    GOAL = goal,
    SCENE = scene,
    COLLISIONS = collisions,
    ROBOT_STATES_TRUE = robot_states_true,
];

/// A per-robot topic helper with its message type erased: robot index to topic name.
pub type RobotTopic = fn(usize) -> String;

/// The per-robot topic helpers of [`crate::topics`], by their Rust names.
pub const ROBOT_TOPICS: &[(&str, RobotTopic)] = topic_names![
    scan,
    imu,
    pose_true,
    twist_true,
    pose,
    odometry,
    wheel_setpoint,
    wheel_state,
    encoder_ticks,
    cmd_vel,
    path,
    joint_states,
    joint_command,
    link_states,
    contacts,
    wrench,
    force_torque,
    ground_truth,
    set_pose,
];

/// All layouts as JSON: `[{name, type_name, size, align, fields: [{name, offset, size, type,
/// len?, count?, text?}]}]`, where `type` is a scalar name (`f64`) or a struct name, `len`
/// marks an array, `count` the fields that count its valid items and `text` a string's bytes.
pub fn layouts_json() -> serde_json::Value {
    serde_json::Value::Array(layouts().iter().map(layout_json).collect())
}

/// The descriptor of the catalog's type named `type_name` (`caravan::Pose2D`), with its default
/// value: the types every process knows without being told (and the bench's blobs, whose
/// default is all zeros). `None` for another type.
pub fn descriptor(type_name: &str) -> Option<&'static Descriptor> {
    // Built once: `caravan play` looks a type up for every message it writes.
    static ALL: std::sync::LazyLock<Vec<Descriptor>> = std::sync::LazyLock::new(|| {
        macro_rules! descriptors {
            ($($ty:ident)*) => { vec![$(crate::descriptor_of::<crate::$ty>()),*] };
        }
        let mut all = crate::message_types!([descriptors] {});
        all.extend([
            crate::descriptor_of::<Header>(),
            crate::descriptor_of::<Hello>(),
            crate::descriptor_of::<Grant>(),
            crate::descriptor_of::<Done>(),
        ]);
        // The bench's blobs cross hosts through the bridge like any topic.
        all.extend(
            crate::bench::layouts()
                .into_iter()
                .map(|l| Descriptor::new(vec![l])),
        );
        all
    });
    ALL.iter().find(|d| d.type_name() == type_name)
}
