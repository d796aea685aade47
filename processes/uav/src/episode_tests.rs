use super::*;
use caravan_schemas::placement_new;

/// The node's first step, ns.
const T0: u64 = 1_000_000_000;

fn e() -> Encounter {
    Encounter::default()
}

fn episodes(n: u64) -> Episodes {
    Episodes::new(e(), Scenario::HEAD_ON, Frame::default(), n, 7)
}

/// The drones' ground truth at encounter positions `agent` and `opponent` (m), the agent
/// flying at cruise speed, the opponent towards it.
fn truth(agent: [f64; 3], opponent: [f64; 3]) -> (Odometry, Odometry) {
    let f = Frame::default();
    let odometry = |at: [f64; 3], vx: f64| {
        let mut o = Odometry {
            pose: f.pose(&at.into()),
            ..Odometry::default()
        };
        o.twist.linear.x = vx;
        o
    };
    (odometry(agent, 1.0), odometry(opponent, -1.0))
}

/// Both drones on course, 4 m apart: nothing ends.
fn on_course() -> (Odometry, Odometry) {
    truth([3.0, 0.0, 2.0], [7.0, 0.0, 2.0])
}

/// The drones touching: a collision.
fn touching() -> (Odometry, Odometry) {
    truth([5.0, 0.0, 2.0], [5.2, 0.0, 2.0])
}

fn discrete(episode: u64, step: u32, a: i32) -> AgentAction {
    let mut m = placement_new::<AgentAction>();
    m.episode = episode;
    m.step = step;
    m.discrete = a;
    m
}

fn continuous(episode: u64, step: u32, a: &[f64]) -> AgentAction {
    let mut m = discrete(episode, step, -1);
    m.continuous.set_from_slice(a);
    m
}

fn metric(summary: &EpisodeEnd, name: &str) -> f64 {
    summary
        .metrics
        .as_slice()
        .iter()
        .find(|m| m.name.as_str() == name)
        .map(|m| m.value)
        .unwrap_or_else(|| panic!("no metric {name}"))
}

#[test]
fn the_first_step_starts_episode_one_once() {
    let (e, f) = (e(), Frame::default());
    let mut env = episodes(3);
    let s = env.start(T0).expect("episode 1 starts");
    assert_eq!(s.set_pose[0], f.pose(&e.agent_start()));
    assert_eq!(s.set_pose[1], f.pose(&e.opponent_start([0.0, 0.0])));
    assert_eq!(s.cmd_vel, twist(&Vector3::new(e.speed_m_s, 0.0, 0.0)));
    let o = &s.observation;
    assert_eq!((o.episode, o.step, o.terminated, o.truncated), (1, 0, 0, 0));
    assert_eq!(o.reward, 0.0);
    // Own velocity (1, 0, 0) and the opponent 10 m ahead, over the 10 m separation.
    assert_eq!(o.observation.as_slice(), [1.0, 0.0, 0.0, 1.0, 0.0, 0.0]);
    assert!(env.start(T0 + 1).is_none());
}

#[test]
fn nothing_happens_before_the_start() {
    let mut env = episodes(1);
    assert!(env.step(T0, Some(on_course())).is_none());
    assert_eq!(env.act(T0, &discrete(1, 0, 1)), Ok(None));
}

#[test]
fn an_action_answers_the_last_observation_once() {
    let mut env = episodes(1);
    env.start(T0);
    assert_eq!(env.act(T0, &discrete(1, 1, 1)), Ok(None), "another step");
    assert_eq!(env.act(T0, &discrete(2, 0, 1)), Ok(None), "another episode");
    let t = env.act(T0, &discrete(1, 0, 1)).unwrap().expect("applied");
    assert_eq!([t.linear.x, t.linear.y, t.linear.z], [1.0, 0.05, 0.0], "+y");
    assert_eq!(env.act(T0, &discrete(1, 0, 1)), Ok(None), "already acted");

    // The next observation takes the next action, from the velocity the last one left.
    let dt = e().step_ns();
    assert!(env.step(T0 + dt, Some(on_course())).is_some());
    let t = env.act(T0 + dt, &discrete(1, 1, 5)).unwrap().unwrap();
    assert_eq!(
        [t.linear.x, t.linear.y, t.linear.z],
        [1.0, 0.1, 0.05],
        "+y+z"
    );
}

#[test]
fn bad_actions_are_named_and_continuous_ones_clipped() {
    let mut env = episodes(1);
    env.start(T0);
    let err = env.act(T0, &discrete(1, 0, 9)).unwrap_err();
    assert!(
        err.starts_with("agent/action: ") && err.contains("0–8"),
        "{err}"
    );
    // Indices beyond a byte are held at 255, still not an action.
    let err = env.act(T0, &discrete(1, 0, 1000)).unwrap_err();
    assert!(err.contains("discrete action 255"), "{err}");
    // A missing component is not a number.
    let err = env.act(T0, &continuous(1, 0, &[0.5])).unwrap_err();
    assert!(err.contains("not finite"), "{err}");
    let t = env
        .act(T0, &continuous(1, 0, &[0.5, -2.0]))
        .unwrap()
        .unwrap();
    assert_eq!(
        [t.linear.y, t.linear.z],
        [0.025, -0.05],
        "z clipped to −1 unit"
    );
}

#[test]
fn agent_steps_keep_their_schedule_and_wait_for_the_truth() {
    let (e, f) = (e(), Frame::default());
    let dt = e.step_ns();
    let mut env = episodes(1);
    env.start(T0);
    assert!(
        env.step(T0 + dt - 1, Some(on_course())).is_none(),
        "not due"
    );
    assert!(env.step(T0 + dt, None).is_none(), "no ground truth yet");

    let s = env.step(T0 + dt + 1000, Some(on_course())).expect("late");
    let (a, o) = on_course();
    let state = f.state(&a, &o, e.step_s);
    let ob = &s.observation;
    assert_eq!(
        (ob.episode, ob.step, ob.terminated, ob.truncated),
        (1, 1, 0, 0)
    );
    assert_eq!(ob.reward, e.reward(&state, None));
    assert_eq!(ob.observation.as_slice(), e.observe(&state));
    assert!(s.end.is_none());

    // The next is due a step after this one was, not after it came late.
    assert!(env.step(T0 + 2 * dt - 1, Some(on_course())).is_none());
    let s = env.step(T0 + 2 * dt, Some(on_course())).unwrap();
    assert_eq!(s.observation.step, 2);
}

#[test]
fn a_collision_ends_the_episode_and_starts_the_next_until_the_last() {
    let dt = e().step_ns();
    let mut env = episodes(2);
    env.start(T0);
    env.act(T0 + 5_000_000, &discrete(1, 0, 0))
        .unwrap()
        .unwrap();
    let s = env.step(T0 + dt, Some(touching())).unwrap();
    let ob = &s.observation;
    assert_eq!(
        (ob.episode, ob.step, ob.terminated, ob.truncated),
        (1, 1, 1, 0)
    );
    assert_eq!(
        ob.reward, -1000.0,
        "on the start line, so only the collision"
    );
    let end = s.end.expect("collided");
    let m = &end.summary;
    assert_eq!((m.episode, m.steps, m.outcome.as_str()), (1, 1, "collided"));
    assert_eq!(m.total_reward, -1000.0);
    assert!((metric(m, "closest_m") - 0.2).abs() < 1e-12);
    assert!((metric(m, "reaction_latency_s") - 0.005).abs() < 1e-15);

    // Episode 2 starts at once, on its own schedule, from cruise speed.
    let next = end.next.expect("episode 2");
    let ob = &next.observation;
    assert_eq!((ob.episode, ob.step, ob.reward), (2, 0, 0.0));
    assert_eq!(
        env.act(T0 + dt, &discrete(1, 1, 1)),
        Ok(None),
        "episode 1 ended"
    );
    let t = env.act(T0 + dt, &discrete(2, 0, 1)).unwrap().unwrap();
    assert_eq!(t.linear.y, 0.05);
    assert!(env.step(T0 + 2 * dt - 1, Some(touching())).is_none());
    let s = env.step(T0 + 2 * dt, Some(touching())).unwrap();
    assert_eq!((s.observation.episode, s.observation.step), (2, 1));
    let end = s.end.expect("collided again");
    assert_eq!(end.summary.episode, 2);
    assert!(end.next.is_none(), "the last episode: done");
}

#[test]
fn the_floor_the_pass_and_the_time_limit_end_episodes_by_name() {
    let short = Encounter {
        time_limit_s: e().step_s,
        ..e()
    };
    let cases = [
        (
            e(),
            truth([3.0, 0.0, 0.05], [7.0, 0.0, 2.0]),
            "floor",
            (1, 0),
        ),
        (
            e(),
            truth([10.0, 0.0, 2.0], [0.0, 3.0, 2.0]),
            "passed",
            (1, 0),
        ),
        (short, on_course(), "timeout", (0, 1)),
    ];
    for (e, t, name, ends) in cases {
        let mut env = Episodes::new(e, Scenario::HEAD_ON, Frame::default(), 1, 7);
        env.start(T0);
        let s = env.step(T0 + e.step_ns(), Some(t)).unwrap();
        let ob = &s.observation;
        assert_eq!((ob.terminated, ob.truncated), ends, "{name}");
        let state = Frame::default().state(&t.0, &t.1, e.step_s);
        assert_eq!(ob.reward, e.reward(&state, e.outcome(&state)), "{name}");
        let end = s.end.expect(name);
        assert_eq!(end.summary.outcome.as_str(), name);
        assert!(end.next.is_none());
    }
}

#[test]
fn start_shifts_are_drawn_from_the_seed_one_episode_after_another() {
    let (e, f) = (e(), Frame::default());
    let s1 = Scenario::named("s1").unwrap();
    let mut g = Gaussian::new(11, 0);
    let (first, second) = (s1.offset(&mut g), s1.offset(&mut g));
    assert_ne!(first, second);

    let mut env = Episodes::new(e, s1, f, 2, 11);
    let start = env.start(T0).unwrap();
    assert_eq!(start.set_pose[1], f.pose(&e.opponent_start(first)));
    let s = env.step(T0 + e.step_ns(), Some(touching())).unwrap();
    let next = s.end.unwrap().next.unwrap();
    assert_eq!(next.set_pose[1], f.pose(&e.opponent_start(second)));
}
