//! Hand-computed cases of the identification.

use super::*;
use crate::planar_arm::PlanarArm;
use std::f64::consts::FRAC_PI_2;

/// Four 1 m links, radius 0.05 m: joints at (0, 0), (1, 0), (1, 1), (2, 1); link 3 runs from
/// (2, 1) to (3, 1).
fn stepped_arm() -> ArmPose {
    PlanarArm::new(Point2::origin(), vec![1.0; 4], 0.05)
        .unwrap()
        .pose(&[0.0, FRAC_PI_2, -FRAC_PI_2, 0.0])
}

fn close(a: Point2<f64>, b: Point2<f64>) -> bool {
    (a - b).norm() < 1e-12
}

#[test]
fn a_push_down_on_link_2_is_found_exactly() {
    let pose = stepped_arm();
    // 10 N straight down on the top of link 2 at x = 1.5: lever arms 1.5, 0.5, 0.5 m.
    let tau = [-15.0, -5.0, -5.0, 0.0];
    assert_eq!(
        pose.torques(2, &Point2::new(1.5, 1.05), &Vector2::new(0.0, -10.0)),
        tau
    );
    let e = identify(&pose, &tau, &[], &Settings::default()).unwrap();
    assert!((e.force - Vector2::new(0.0, -10.0)).norm() < 1e-12, "{e:?}");
    assert!(close(e.point.unwrap(), Point2::new(1.5, 1.05)), "{e:?}");
    assert_eq!((e.link, e.source), (2, Some(PointSource::Line)));
    // Joint 3's zero torque rules link 3 out: the line x = 1.5 misses its axis.
    assert_eq!((e.candidates.k_min, e.candidates.k_max), (2, 2));
}

#[test]
fn the_extended_wrench_is_the_force_for_any_reference_point() {
    let pose = stepped_arm();
    let tau = [-15.0, -5.0, -5.0];
    let w = extended_wrench(&pose.joints, &tau, 1e-6).unwrap();
    assert!((w.force() - Vector2::new(0.0, -10.0)).norm() < 1e-12);
    assert!(w.residual < 1e-12);
    // The line of action is x = 1.5.
    assert!((w.line_point().x - 1.5).abs() < 1e-12);
}

#[test]
fn a_line_through_a_joint_axis_widens_the_candidates_and_the_surface_decides() {
    let pose = stepped_arm();
    // 10 N along −x on the tip of link 3: the line y = 1 runs through joints 2 and 3, so
    // their torques vanish as if link 1 were touched.
    let tip = pose.contours[3]
        .entry(&Point2::new(4.0, 1.0), &Vector2::new(-1.0, 0.0))
        .unwrap()
        .point;
    let tau = pose.torques(3, &tip, &Vector2::new(-10.0, 0.0));
    assert_eq!(tau, [10.0, 10.0, 0.0, 0.0]);
    let e = identify(&pose, &tau, &[], &Settings::default()).unwrap();
    assert_eq!((e.candidates.k_min, e.candidates.k_max), (1, 3));
    // The line enters links 1 and 2 only inside their neighbours: link 3's tip it is.
    assert_eq!(e.link, 3);
    assert!(close(e.point.unwrap(), tip), "{e:?}");
    assert!((e.force - Vector2::new(-10.0, 0.0)).norm() < 1e-12);
}

#[test]
fn the_depth_sensor_picks_among_valid_candidates() {
    let valid = [(2, Point2::new(1.5, 1.05)), (3, Point2::new(2.5, 1.05))];
    // Blind: the most distal.
    assert_eq!(choose(&valid, &[]), Some(valid[1]));
    // The obstacle is seen next to link 2's point.
    assert_eq!(
        choose(&valid, &[Point2::new(3.0, 3.0), Point2::new(1.45, 1.12)]),
        Some(valid[0])
    );
    assert_eq!(
        choose(&valid[..1], &[Point2::new(2.5, 1.1)]),
        Some(valid[0])
    );
    assert_eq!(choose(&[], &[Point2::new(2.5, 1.1)]), None);
}

#[test]
fn a_line_that_misses_the_surface_keeps_the_force_and_takes_the_point_from_depth() {
    let pose = stepped_arm();
    // 10 N along +x acting 0.45 m above link 2: the line y = 1.5 misses every link.
    let tau = pose.torques(2, &Point2::new(1.5, 1.5), &Vector2::new(10.0, 0.0));
    let blind = identify(&pose, &tau, &[], &Settings::default()).unwrap();
    assert!((blind.force - Vector2::new(10.0, 0.0)).norm() < 1e-12);
    assert_eq!((blind.point, blind.source), (None, None));
    let seen = identify(&pose, &tau, &[Point2::new(1.5, 1.2)], &Settings::default()).unwrap();
    assert_eq!((seen.link, seen.source), (2, Some(PointSource::Depth)));
    assert!(
        close(seen.point.unwrap(), Point2::new(1.5, 1.05)),
        "{seen:?}"
    );
}

#[test]
fn a_force_outside_the_friction_cone_has_no_entry_point() {
    let pose = stepped_arm();
    // 40° from the normal with μ = 0.5 (cone half-angle 26.6°).
    let a = 40f64.to_radians();
    let f = Vector2::new(10.0 * a.sin(), -10.0 * a.cos());
    let tau = pose.torques(2, &Point2::new(1.5, 1.05), &f);
    let e = identify(&pose, &tau, &[], &Settings::default()).unwrap();
    assert_eq!(e.source, None);
    // With μ = 1 (45°) the same push is explained.
    let wide = Settings {
        mu: 1.0,
        ..Settings::default()
    };
    let e = identify(&pose, &tau, &[], &wide).unwrap();
    assert!(close(e.point.unwrap(), Point2::new(1.5, 1.05)), "{e:?}");
}

#[test]
fn collinear_axes_and_silent_joints_give_no_force() {
    let straight = PlanarArm::new(Point2::origin(), vec![1.0; 4], 0.05)
        .unwrap()
        .pose(&[0.0; 4]);
    // A push down on the stretched arm's link 3: every axis lies on the line y = 0.
    let tau = straight.torques(3, &Point2::new(3.5, 0.05), &Vector2::new(0.0, -10.0));
    assert_eq!(
        identify(&straight, &tau, &[], &Settings::default()),
        Err(NoForce::Underdetermined)
    );
    assert_eq!(
        identify(&stepped_arm(), &[0.0; 4], &[], &Settings::default()),
        Err(NoForce::NoContact)
    );
    // Two pushes (links 2 and 3) fit no single force.
    let pose = stepped_arm();
    let a = pose.torques(2, &Point2::new(1.5, 1.05), &Vector2::new(0.0, -10.0));
    let b = pose.torques(3, &Point2::new(2.5, 0.95), &Vector2::new(0.0, 10.0));
    let tau: Vec<f64> = a.iter().zip(&b).map(|(a, b)| a + b).collect();
    assert_eq!(
        identify(&pose, &tau, &[], &Settings::default()),
        Err(NoForce::Inconsistent)
    );
}

#[test]
fn noise_raises_the_thresholds() {
    let s = Settings {
        torque_sigma: 0.5,
        ..Settings::default()
    };
    assert!((s.delta_tau() - 1.5).abs() < 1e-6);
    assert!((s.delta_eps(5) - 1.5 * 2f64.sqrt()).abs() < 1e-6);
    // A joint torque within the noise does not make its link a candidate.
    let pose = stepped_arm();
    let mut tau = pose.torques(2, &Point2::new(1.5, 1.05), &Vector2::new(0.0, -10.0));
    tau[3] = 0.4;
    let e = identify(&pose, &tau, &[], &s).unwrap();
    assert_eq!(e.candidates.k_min, 2);
}
