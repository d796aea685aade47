//! The bridge node: at each of its steps it publishes the group's time on `/clock`, forwards
//! every message that reached its Caravan subscribers to ROS 2 (stamped with the message's
//! own simulated time), and publishes into the group every ROS 2 message that arrived since
//! the last step. In lockstep it is a member of the schedule like any node, so what leaves
//! for ROS 2 is deterministic; what comes in joins at the bridge's next step after it arrives,
//! which depends on the wall clock (a ROS 2 node is a realtime participant, docs/ros2.md).

use crate::config::{Config, Durability, Qos, Reliability, Route};
use crate::mapping::{self, Caravan, RosMessage};
use crate::msgs;
use crate::ros_type::{RosType, Way};
use caravan::{Error, Node, Publisher, Subscriber, Topic, Trigger};
use caravan_schemas as cv;
use ros2_client::{Context, MessageTypeName, Name, NodeName, NodeOptions, QosProfile};
use std::collections::BTreeMap;

/// The bridge's default rate: the physics' and the sensors' 100 Hz.
pub const DEFAULT_HZ: f64 = 100.0;

macro_rules! sources {
    ($($ty:ident),*) => {
        /// A Caravan subscriber of a type that crosses out.
        enum Source { $($ty(Subscriber<cv::$ty>)),* }

        impl Source {
            fn open(node: &Node, topic: &str, type_name: &str) -> Result<Source, Error> {
                $(if type_name == cv::type_name::<cv::$ty>() {
                    return Ok(Source::$ty(node.subscriber(&Topic::<cv::$ty>::new(topic))?));
                })*
                Err(Error::Config(format!("{topic}: {type_name} does not cross to ROS 2")))
            }

            /// Calls `f` with each message received since the last call, and its stamp.
            fn drain(&self, f: &mut dyn FnMut(u64, Caravan)) -> Result<(), Error> {
                match self {
                    $(Source::$ty(s) => {
                        while let Some(m) = s.receive()? {
                            f(m.header().stamp_ns, Caravan::$ty(&m));
                        }
                    })*
                }
                Ok(())
            }
        }
    };
}

crate::mapping::outbound_types!(sources);

/// A ROS 2 subscription and the Caravan publisher its messages go to.
enum Sink {
    Twist(ros2_client::Subscription<msgs::Twist>, Publisher<cv::Twist>),
    Pose2D(
        ros2_client::Subscription<msgs::Pose2D>,
        Publisher<cv::Pose2D>,
    ),
    PlanarPose(
        ros2_client::Subscription<msgs::PoseStamped>,
        Publisher<cv::Pose2D>,
    ),
    Pose3D(
        ros2_client::Subscription<msgs::PoseStamped>,
        Publisher<cv::Pose3D>,
    ),
    Wrench(
        ros2_client::Subscription<msgs::WrenchStamped>,
        Publisher<cv::Wrench>,
    ),
    Joints(
        ros2_client::Subscription<msgs::JointState>,
        Publisher<cv::JointCommand>,
    ),
}

/// Takes every sample `sub` holds, publishing each converted; a sample that does not decode is
/// reported once per step and skipped.
fn forward<M: serde::de::DeserializeOwned + 'static, T: caravan_schemas::Message>(
    sub: &ros2_client::Subscription<M>,
    out: &Publisher<T>,
    convert: impl Fn(&M) -> Box<T>,
) -> Result<(), Error> {
    loop {
        match sub.take() {
            Ok(Some((m, _))) => out.publish(&convert(&m))?,
            Ok(None) => return Ok(()),
            Err(e) => {
                eprintln!(
                    "caravan-ros2: {}: a ROS 2 message did not decode: {e:?}",
                    out.topic()
                );
                return Ok(());
            }
        }
    }
}

impl Sink {
    fn drain(&self) -> Result<(), Error> {
        match self {
            Sink::Twist(s, p) => forward(s, p, |m| Box::new(mapping::twist_in(m))),
            Sink::Pose2D(s, p) => forward(s, p, |m| Box::new(mapping::pose_2d_in(m))),
            Sink::PlanarPose(s, p) => forward(s, p, |m| Box::new(mapping::pose_planar_in(&m.pose))),
            Sink::Pose3D(s, p) => forward(s, p, |m| Box::new(mapping::pose_3d_in(&m.pose))),
            Sink::Wrench(s, p) => forward(s, p, |m| Box::new(mapping::wrench_in(m))),
            Sink::Joints(s, p) => forward(s, p, mapping::joint_command_in),
        }
    }
}

fn qos(q: &Qos) -> QosProfile {
    use ros2_client::qos::{self, History, WhenFull};
    // A full reliable writer drops instead of blocking: the bridge never holds up the group.
    let reliability = match q.reliability {
        Reliability::Reliable => qos::Reliability::Reliable {
            when_full: WhenFull::Fail,
        },
        Reliability::BestEffort => qos::Reliability::BestEffort,
    };
    let durability = match q.durability {
        Durability::Volatile => qos::Durability::Volatile,
        Durability::TransientLocal => qos::Durability::TransientLocal,
    };
    QosProfile::publisher_default()
        .reliability(reliability)
        .durability(durability)
        .history(History::KeepLast {
            depth: q.depth as usize,
        })
}

fn dds(what: &str, e: impl std::fmt::Debug) -> Error {
    Error::Transport(format!("ROS 2 (DDS) {what}: {e:?}"))
}

/// The ROS 2 node name of a Caravan process (`ros2-bridge` → `ros2_bridge`, in `/caravan`).
fn node_name(name: &str) -> String {
    let clean: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if clean.starts_with(|c: char| c.is_ascii_alphabetic()) {
        clean
    } else {
        format!("n_{clean}")
    }
}

/// Runs the bridge until the group stops it.
pub fn run(mut node: Node, config: Config) -> Result<(), Error> {
    let context =
        Context::with_options(ros2_client::ContextOptions::new().domain_id(config.domain))
            .map_err(|e| dds("domain participant", e))?;
    let mut ros = context
        .new_node(
            NodeName::new("/caravan", &node_name(node.name())).map_err(|e| dds("node name", e))?,
            NodeOptions::new().enable_rosout(false),
        )
        .map_err(|e| dds("node", e))?;
    let topic = |ros: &mut ros2_client::Node, name: &str, ty: RosType, q: &QosProfile| {
        let (package, type_name) = ty.parts();
        let parsed = Name::parse(name).map_err(|e| dds(name, e))?;
        ros.create_topic(&parsed, MessageTypeName::new(package, type_name), q)
            .map_err(|e| dds(name, e))
    };
    let clock = if config.clock {
        let q = qos(&Qos {
            depth: 1,
            ..Qos::default()
        });
        let t = topic(&mut ros, "/clock", RosType::Clock, &q)?;
        Some(
            ros.create_publisher::<RosMessage>(&t, None)
                .map_err(|e| dds("/clock", e))?,
        )
    } else {
        None
    };
    // One publisher per ROS topic: several entries may feed one (every robot's poses → /tf).
    let mut writers: BTreeMap<String, ros2_client::Publisher<RosMessage>> = BTreeMap::new();
    let mut outs: Vec<(Route, Source)> = Vec::new();
    let mut sinks: Vec<Sink> = Vec::new();
    for route in &config.routes {
        let q = qos(&route.qos);
        let t = topic(&mut ros, &route.ros, route.ty, &q)?;
        match route.way {
            Way::Out => {
                if !writers.contains_key(&route.ros) {
                    let w = ros
                        .create_publisher(&t, None)
                        .map_err(|e| dds(&route.ros, e))?;
                    writers.insert(route.ros.clone(), w);
                }
                outs.push((
                    route.clone(),
                    Source::open(&node, &route.caravan, route.caravan_type)?,
                ));
            }
            Way::In => sinks.push(sink(&mut ros, &node, route, &t)?),
        }
    }
    let trigger = node.trigger(Trigger::every_hz(DEFAULT_HZ))?;
    node.run(trigger, |step| {
        if let Some(clock) = &clock {
            // A lost /clock sample is replaced by the next step's.
            let _ = clock.publish(mapping::clock(step.now_ns()));
        }
        for (route, source) in &outs {
            let writer = &writers[&route.ros];
            source.drain(&mut |stamp, msg| {
                if let Some(m) = mapping::to_ros(route.ty, msg, stamp, &route.frames)
                    && let Err(e) = writer.publish(m)
                {
                    eprintln!("caravan-ros2: {}: not sent: {e:?}", route.ros);
                }
            })?;
        }
        for s in &sinks {
            s.drain()?;
        }
        Ok(())
    })?;
    Ok(())
}

fn sink(
    ros: &mut ros2_client::Node,
    node: &Node,
    route: &Route,
    t: &ros2_client::dds::rustdds::Topic,
) -> Result<Sink, Error> {
    macro_rules! subscribe {
        () => {
            ros.create_subscription(t, None)
                .map_err(|e| dds(&route.ros, e))?
        };
    }
    Ok(match (route.ty, route.caravan_type) {
        (RosType::Twist, _) => {
            Sink::Twist(subscribe!(), node.publisher(&Topic::new(&route.caravan))?)
        }
        (RosType::Pose2D, _) => {
            Sink::Pose2D(subscribe!(), node.publisher(&Topic::new(&route.caravan))?)
        }
        (RosType::PoseStamped, "caravan::Pose3D") => {
            Sink::Pose3D(subscribe!(), node.publisher(&Topic::new(&route.caravan))?)
        }
        (RosType::PoseStamped, _) => {
            Sink::PlanarPose(subscribe!(), node.publisher(&Topic::new(&route.caravan))?)
        }
        (RosType::WrenchStamped, _) => {
            Sink::Wrench(subscribe!(), node.publisher(&Topic::new(&route.caravan))?)
        }
        (RosType::JointState, _) => {
            Sink::Joints(subscribe!(), node.publisher(&Topic::new(&route.caravan))?)
        }
        (ty, _) => {
            let message = format!("{}: {} does not cross in", route.caravan, ty.name());
            return Err(Error::Config(message));
        }
    })
}
