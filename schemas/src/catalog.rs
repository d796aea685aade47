//! The catalog of the shared message types: every type that crosses a process boundary (the
//! registry's message types, the [`Header`] and the lockstep protocol's messages) with its
//! layout, and the topics of [`crate::topics`] by the names other languages give them.
//! `caravan schemas --python` and `--layout` print it.

use crate::describe::{Describe, TypeLayout};
use crate::descriptor::{Descriptor, layout_json};
use crate::lockstep::{Done, Grant, Hello};
use crate::{
    AgentAction, Collision, Contact, ContactEstimate, Contacts, EncoderTicks, EnvStep, EpisodeEnd,
    ForceTorque, ForceTorques, Goal, Header, Imu, JointCommand, JointState, JointValue, LaserScan,
    LinkState, LinkStates, Metrics, NamedValue, NodeStatus, OccupancyGrid, Odometry, Path2D,
    Pose2D, Pose3D, Quaternion, Scene, Shape, Twist, Vector3, WheelSetpoint, WheelState, Wrench,
};

/// Runs `$apply!(Type …)` over every type of the catalog, each after the types it contains.
macro_rules! catalog {
    ($apply:ident) => {
        $apply!(Header Vector3 Quaternion Pose2D Pose3D Twist WheelSetpoint WheelState EncoderTicks
            Odometry LaserScan Imu OccupancyGrid Path2D Goal Shape Scene NodeStatus Collision
            JointValue JointState JointCommand LinkState LinkStates Contact Contacts Wrench
            ForceTorque ForceTorques ContactEstimate EnvStep AgentAction NamedValue EpisodeEnd
            Metrics Hello Grant Done)
    };
}

/// Every described type, each after the types it contains.
pub fn layouts() -> Vec<TypeLayout> {
    macro_rules! layouts {
        ($($ty:ident)*) => { vec![$(<$ty as Describe>::layout()),*] };
    }
    catalog!(layouts)
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
    AGENT_OBSERVATION = agent_observation,
    AGENT_ACTION = agent_action,
    AGENT_EPISODE = agent_episode,
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
    contact_estimate,
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
            ($($ty:ident)*) => { vec![$(crate::descriptor_of::<$ty>()),*] };
        }
        let mut all = catalog!(descriptors);
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
