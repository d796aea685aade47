//! What a robot rests on at the end of a run: the share of its contact force the chassis
//! (`base_link`) bears, from the recorded `robot/0/contacts`. A stuck tracked robot whose
//! chassis bears a large share is high-centred: its belly sits on a block and its tracks,
//! lightened, lose their grip. One whose chassis bears nothing is wedged on its wheels.

/// The contacts topic of the scenario's robot (physics `contacts = true`).
pub const CONTACTS_TOPIC: &str = "robot/0/contacts";
/// The chassis' link.
pub const CHASSIS_LINK: &str = "base_link";
/// The span at the end of the run that is averaged, s: long enough to smooth a step's
/// jitter, short enough to describe where the robot came to rest.
pub const END_SPAN_S: f64 = 5.0;

/// A chassis bearing more than this share is called high-centred in the report (chosen: a
/// third of the load off the tracks; stuck runs on the hills bear 0 % or 41–82 %).
pub const HIGH_CENTRED_SHARE: f64 = 1.0 / 3.0;

/// One physics step's contact forces: (time s, [(link, normal force N)]).
pub type Step = (f64, Vec<(String, f64)>);

/// The chassis' share (0–1) of the summed normal force over the last [`END_SPAN_S`] of
/// `steps` (in time order); `None` without steps or with no force in that span.
pub fn chassis_share(steps: &[Step]) -> Option<f64> {
    let end = steps.last()?.0;
    let (mut chassis, mut all) = (0.0, 0.0);
    for (_, forces) in steps.iter().filter(|(t, _)| *t >= end - END_SPAN_S) {
        for (link, f) in forces {
            all += f;
            if link == CHASSIS_LINK {
                chassis += f;
            }
        }
    }
    (all > 0.0).then_some(chassis / all)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(t: f64, forces: &[(&str, f64)]) -> Step {
        (t, forces.iter().map(|(l, f)| (l.to_string(), *f)).collect())
    }

    #[test]
    fn the_share_is_the_chassis_force_over_all_in_the_last_seconds() {
        let steps = [
            // Before the end span: the chassis bore everything, and is left out.
            step(1.0, &[("base_link", 100.0)]),
            step(26.0, &[("base_link", 60.0), ("left_main_0_wheel", 20.0)]),
            step(30.0, &[("right_main_3_wheel", 40.0), ("base_link", 20.0)]),
        ];
        assert_eq!(chassis_share(&steps), Some(80.0 / 140.0));
    }

    #[test]
    fn wheels_alone_give_zero_and_no_force_gives_none() {
        assert_eq!(
            chassis_share(&[step(3.0, &[("left_main_0_wheel", 50.0)])]),
            Some(0.0)
        );
        assert_eq!(chassis_share(&[step(3.0, &[])]), None);
        assert_eq!(chassis_share(&[]), None);
    }
}
