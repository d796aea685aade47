use super::*;
use crate::msgs::{self, from_cdr};

fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("caravan-bag-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn scan(stamp_ns: u64, ranges: &[f32]) -> RosMessage {
    RosMessage::LaserScan(msgs::LaserScan {
        header: msgs::Header {
            stamp: msgs::Time::from_ns(stamp_ns),
            frame_id: "robot_0/base_link".into(),
        },
        ranges: ranges.to_vec(),
        ..Default::default()
    })
}

/// A bag of two scans, a twist and a topic without messages.
fn write_sample(dir: &Path) -> Written {
    let mut w = BagWriter::create(dir).unwrap();
    w.add_topic("/robot_0/scan", RosType::LaserScan, &offered_qos(false, 10))
        .unwrap();
    w.add_topic("/map", RosType::OccupancyGrid, &offered_qos(true, 1))
        .unwrap();
    w.add_topic("/robot_0/cmd_vel", RosType::Twist, &offered_qos(false, 10))
        .unwrap();
    w.write_message(
        "/robot_0/scan",
        100_000_000,
        &scan(100_000_000, &[1.0, 2.0]),
    )
    .unwrap();
    let twist = RosMessage::Twist(msgs::Twist {
        linear: msgs::Vector3 {
            x: 0.5,
            ..Default::default()
        },
        ..Default::default()
    });
    w.write_message("/robot_0/cmd_vel", 150_000_000, &twist)
        .unwrap();
    w.write_message("/robot_0/scan", 1_200_000_000, &scan(1_200_000_000, &[3.0]))
        .unwrap();
    w.finish().unwrap()
}

#[test]
fn a_bag_reads_back_as_written() {
    let root = scratch("round-trip");
    let dir = root.join("out_bag");
    let written = write_sample(&dir);
    assert_eq!(written.messages, 3);
    assert_eq!(written.file, dir.join("out_bag_0.mcap"));
    assert_eq!(
        written.topics[0],
        ("/robot_0/scan".to_string(), RosType::LaserScan, 2)
    );
    for path in [dir.clone(), written.file.clone()] {
        let bag = read_bag(&path).unwrap();
        assert_eq!(bag.topics.len(), 3, "the map has no message but is listed");
        assert_eq!(bag.topics["/map"], RosType::OccupancyGrid);
        let times: Vec<(&str, u64)> = bag
            .messages
            .iter()
            .map(|m| (m.topic.as_str(), m.log_ns))
            .collect();
        assert_eq!(
            times,
            [
                ("/robot_0/scan", 100_000_000),
                ("/robot_0/cmd_vel", 150_000_000),
                ("/robot_0/scan", 1_200_000_000)
            ]
        );
        let last: msgs::LaserScan = from_cdr(&bag.messages[2].cdr).unwrap();
        assert_eq!(last.ranges, [3.0]);
        assert_eq!(
            last.header.stamp,
            msgs::Time {
                sec: 1,
                nanosec: 200_000_000
            }
        );
    }
    assert!(is_bag(&dir) && is_bag(&written.file));
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn the_metadata_is_what_rosbag2_writes() {
    let root = scratch("metadata");
    let dir = root.join("b");
    write_sample(&dir);
    let text = std::fs::read_to_string(dir.join("metadata.yaml")).unwrap();
    let y: serde_yaml::Value = serde_yaml::from_str(&text).unwrap();
    let info = &y["rosbag2_bagfile_information"];
    assert_eq!(info["version"].as_u64(), Some(5));
    assert_eq!(info["storage_identifier"].as_str(), Some("mcap"));
    assert_eq!(info["relative_file_paths"][0].as_str(), Some("b_0.mcap"));
    assert_eq!(info["message_count"].as_u64(), Some(3));
    assert_eq!(
        info["starting_time"]["nanoseconds_since_epoch"].as_u64(),
        Some(100_000_000)
    );
    assert_eq!(
        info["duration"]["nanoseconds"].as_u64(),
        Some(1_100_000_000)
    );
    let map = &info["topics_with_message_count"][1];
    assert_eq!(map["message_count"].as_u64(), Some(0));
    let m = &map["topic_metadata"];
    assert_eq!(
        (
            m["name"].as_str(),
            m["type"].as_str(),
            m["serialization_format"].as_str()
        ),
        (
            Some("/map"),
            Some("nav_msgs/msg/OccupancyGrid"),
            Some("cdr")
        )
    );
    // The offered QoS is itself YAML, as rosbag2 (version 5) keeps it.
    let qos: serde_yaml::Value =
        serde_yaml::from_str(m["offered_qos_profiles"].as_str().unwrap()).unwrap();
    assert_eq!(qos[0]["durability"].as_u64(), Some(1), "transient local");
    assert_eq!(qos[0]["depth"].as_u64(), Some(1));

    // The MCAP file: profile ros2, ros2msg schemas, cdr channels with their QoS.
    let bytes = std::fs::read(dir.join("b_0.mcap")).unwrap();
    assert_eq!(mcap_profile(&bytes), Some("ros2"));
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    for c in summary.channels.values() {
        let s = c.schema.as_ref().unwrap();
        assert_eq!(
            (s.encoding.as_str(), c.message_encoding.as_str()),
            ("ros2msg", "cdr")
        );
        let ty = RosType::parse(&s.name).unwrap();
        assert_eq!(s.name, ty.name());
        assert_eq!(&s.data[..], ty.definition().as_bytes());
        assert!(c.metadata["offered_qos_profiles"].starts_with("- history: 1"));
    }
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn a_bag_is_never_written_over() {
    let root = scratch("exists");
    let e = BagWriter::create(&root).err().unwrap();
    assert!(e.to_string().contains("cannot create"), "{e}");
    let e = BagWriter::create(&root.join("no/such/parent"))
        .err()
        .unwrap();
    assert!(e.to_string().contains("no/such/parent"), "{e}");
    let _ = std::fs::remove_dir_all(&root);
}

/// A rosbag2 MCAP file with one message of type `type_name` on `/points`.
fn foreign_bag(path: &Path, profile: &str, type_name: &str) {
    let mut w = mcap::WriteOptions::new()
        .profile(profile)
        .create(BufWriter::new(File::create(path).unwrap()))
        .unwrap();
    let schema = w.add_schema(type_name, "ros2msg", b"int32 x\n").unwrap();
    let channel = w
        .add_channel(schema, "/points", "cdr", &BTreeMap::new())
        .unwrap();
    let header = mcap::records::MessageHeader {
        channel_id: channel,
        sequence: 1,
        log_time: 5,
        publish_time: 5,
    };
    w.write_to_known_channel(&header, &[0, 1, 0, 0, 7, 0, 0, 0])
        .unwrap();
    w.finish().unwrap();
}

#[test]
fn an_unknown_type_is_refused_naming_it_and_the_file() {
    let root = scratch("unknown");
    let file = root.join("points.mcap");
    foreign_bag(&file, "ros2", "sensor_msgs/msg/PointCloud2");
    let e = read_bag(&file).unwrap_err().to_string();
    assert!(e.contains("points.mcap"), "{e}");
    assert!(
        e.contains("sensor_msgs/msg/PointCloud2") && e.contains("/points"),
        "{e}"
    );
    // A directory says it in its metadata already.
    let dir = root.join("b");
    write_sample(&dir);
    let meta = dir.join("metadata.yaml");
    let text = std::fs::read_to_string(&meta).unwrap();
    std::fs::write(
        &meta,
        text.replace("geometry_msgs/msg/Twist", "my_msgs/msg/Thing"),
    )
    .unwrap();
    let e = read_bag(&dir).unwrap_err().to_string();
    assert!(
        e.contains("metadata.yaml") && e.contains("my_msgs/msg/Thing"),
        "{e}"
    );
    // Another MCAP file is not a bag.
    foreign_bag(&file, "", "sensor_msgs/msg/LaserScan");
    assert!(!is_bag(&file));
    let e = read_bag(&file).unwrap_err().to_string();
    assert!(e.contains("not a rosbag2 file"), "{e}");
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn a_truncated_or_damaged_bag_is_an_error_naming_the_file_never_a_panic() {
    let root = scratch("truncated");
    let dir = root.join("b");
    let written = write_sample(&dir);
    let whole = std::fs::read(&written.file).unwrap();
    let cut = root.join("cut.mcap");
    // Every length short of the whole file: the footer's magic is gone, so none is whole.
    for len in (0..whole.len()).step_by(7).chain([whole.len() - 1]) {
        std::fs::write(&cut, &whole[..len]).unwrap();
        let e = read_bag(&cut).unwrap_err().to_string();
        assert!(e.contains("cut.mcap"), "{len}: {e}");
    }
    // A flipped byte in the middle of the data.
    let mut bad = whole.clone();
    let mid = bad.len() / 2;
    bad[mid] ^= 0xff;
    std::fs::write(&cut, &bad).unwrap();
    if let Err(e) = read_bag(&cut) {
        assert!(e.to_string().contains("cut.mcap"), "{e}");
    }
    std::fs::write(&written.file, &whole[..whole.len() / 2]).unwrap();
    let e = read_bag(&dir).unwrap_err().to_string();
    assert!(e.contains("b_0.mcap") && e.contains("truncated"), "{e}");
    std::fs::remove_file(dir.join("metadata.yaml")).unwrap();
    let e = read_bag(&dir).unwrap_err().to_string();
    assert!(e.contains("without metadata.yaml"), "{e}");
    let _ = std::fs::remove_dir_all(&root);
}
