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

/// One physics step's contact forces, summed: the chassis' and all links', N.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// Simulated time, s.
    pub t_s: f64,
    pub chassis_n: f64,
    pub all_n: f64,
}

impl Step {
    /// The step at `t_s` with these (link, normal force N) contacts.
    pub fn new<'a>(t_s: f64, forces: impl IntoIterator<Item = (&'a str, f64)>) -> Self {
        let mut step = Self {
            t_s,
            chassis_n: 0.0,
            all_n: 0.0,
        };
        for (link, f) in forces {
            step.all_n += f;
            if link == CHASSIS_LINK {
                step.chassis_n += f;
            }
        }
        step
    }
}

/// The chassis' share (0–1) of the summed normal force over the last [`END_SPAN_S`] of
/// `steps` (in time order); `None` without steps or with no force in that span.
pub fn chassis_share(steps: &[Step]) -> Option<f64> {
    let end = steps.last()?.t_s;
    let (chassis, all) = steps
        .iter()
        .filter(|s| s.t_s >= end - END_SPAN_S)
        .fold((0.0, 0.0), |(c, a), s| (c + s.chassis_n, a + s.all_n));
    (all > 0.0).then_some(chassis / all)
}

/// Whether a run that ended `stuck` with the chassis bearing `share` is high-centred.
pub fn high_centred(stuck: bool, share: f64) -> bool {
    stuck && share > HIGH_CENTRED_SHARE
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(t: f64, forces: &[(&str, f64)]) -> Step {
        Step::new(t, forces.iter().copied())
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
