//! Layouts are part of the cross-language contract: Python and C read these offsets. A change
//! here must be deliberate.
use super::*;
use core::mem::{align_of, offset_of, size_of};

const _: () = {
    assert!(size_of::<Header>() == 32 && align_of::<Header>() == 8);
    assert!(size_of::<Pose2D>() == 24);
    assert!(size_of::<Pose3D>() == 56);
    assert!(size_of::<Twist>() == 48);
    assert!(size_of::<WheelSetpoint>() == 16);
    assert!(size_of::<WheelState>() == 48);
    assert!(size_of::<EncoderTicks>() == 24);
    assert!(size_of::<Odometry>() == 56 + 288 + 48 + 288);
    assert!(size_of::<LaserScan>() == 32 + 2 * 4 * SCAN_MAX_BEAMS);
    assert!(align_of::<LaserScan>() == 4);
    assert!(size_of::<Imu>() == 32 + 72 + 24 + 72 + 24 + 72);
    assert!(size_of::<OccupancyGrid>() == 8 + 24 + 8 + MAP_MAX_CELLS);
    assert!(size_of::<Path2D>() == 8 + 24 * PATH_MAX_POSES);
    assert!(size_of::<Goal>() == 40);
    assert!(size_of::<Collision>() == 16);
    assert!(size_of::<JointValue>() == 64 + 24);
    assert!(size_of::<JointState>() == 8 + 88 * MAX_JOINTS);
    assert!(size_of::<LinkState>() == 64 + 56 + 48);
    assert!(size_of::<Contact>() == 64 + 4 + 64 + 4 + 24 + 24 + 8);
    assert!(size_of::<Wrench>() == 64 + 8 + 3 * 24 + 8);
    assert!(size_of::<ForceTorque>() == 64 + 2 * 24);
    assert!(size_of::<RobotState>() == 24 + 48);
    assert!(size_of::<RobotStates>() == 8 + 72 * MAX_ROBOT_STATES);
    assert!(offset_of!(LaserScan, ranges) == 32);
    assert!(offset_of!(OccupancyGrid, data) == 40);
    // `container` took what was padding: a Hello of a build before it is read the same.
    // `output_depth` and a reserved word came at the end (grants of several periods).
    assert!(size_of::<lockstep::Hello>() == 12408);
    assert!(offset_of!(lockstep::Hello, output_depth) == 12400);
    assert!(size_of::<lockstep::Grant>() == 32);
    assert!(offset_of!(lockstep::Grant, until_ns) == 24);
    // `flags` took the reserved word: the size is unchanged.
    assert!(offset_of!(lockstep::Done, flags) + 4 == size_of::<lockstep::Done>());
    assert!(offset_of!(lockstep::Hello, container) == 68);
    assert!(offset_of!(lockstep::Hello, period_ns) == 72);
};

#[test]
fn type_names_are_stable() {
    assert_eq!(type_name::<LaserScan>(), "caravan::LaserScan");
    assert_eq!(type_name::<OccupancyGrid>(), "caravan::OccupancyGrid");
    assert_eq!(type_name::<Header>(), "caravan::Header");
}

#[test]
fn yaw_round_trips_through_quaternion() {
    for yaw in [-3.0, -1.0, 0.0, 0.5, 3.1] {
        assert!((Quaternion::from_yaw(yaw).yaw() - yaw).abs() < 1e-12);
    }
}

#[test]
fn fixed_containers_truncate_at_capacity() {
    let s = FixedString::<4>::new("héllo");
    assert_eq!(s.as_str(), "hél");
    let mut v = FixedVec::<u64, 2>::new();
    assert!(v.push(1).is_ok() && v.push(2).is_ok());
    assert_eq!(v.push(3), Err(3));
    assert_eq!(v.as_slice(), &[1, 2]);
}
