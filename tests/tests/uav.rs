//! Two-UAV collision avoidance: episodes run inside one lockstep group (physics, environment,
//! scripted opponent, policy process), ended by the environment after a number of episodes;
//! the report counts the outcomes.

use caravan_tests::{launch_with_set, launch_with_sets, run_scenario};
use serde_json::Value;

fn uav(policy: &str, scenario: &str, episodes: u32) -> Value {
    let run = run_scenario(
        "uav",
        "encounter.toml",
        &[
            "--set",
            &format!("args.policy={policy}"),
            "--set",
            &format!("args.scenario={scenario}"),
            "--set",
            &format!("args.episodes={episodes}"),
        ],
    );
    assert_eq!(
        run.report["run"]["outcome"], "completed",
        "{}",
        run.report["run"]
    );
    let u = run.report["uav"].clone();
    assert_eq!(u["episodes"], episodes, "{u}");
    u
}

#[test]
fn doing_nothing_head_on_collides_in_every_episode() {
    let u = uav("do_nothing", "head_on", 4);
    assert_eq!(u["outcomes"]["collided"]["count"], 4, "{u}");
    // Head-on: the centres come within the collision radius.
    assert!(
        u["metrics"]["closest_m"]["max"].as_f64().unwrap() < 0.5,
        "{u}"
    );
}

#[test]
fn the_side_step_passes_shifted_straight_opponents() {
    let u = uav("side_step", "s1", 8);
    assert_eq!(u["outcomes"]["passed"]["count"], 8, "{u}");
    assert!(
        u["metrics"]["closest_m"]["min"].as_f64().unwrap() >= 0.5,
        "{u}"
    );
    // The agent left its line and came back toward it: a deviation, but under a metre.
    let dev = u["metrics"]["max_deviation_m"]["mean"].as_f64().unwrap();
    assert!(dev > 0.1 && dev < 1.0, "{u}");
}

#[test]
fn bad_uav_params_name_the_key() {
    for (set, key) in [
        ("args.scenario=s4", "scenario"),
        ("args.episodes=0", "episodes"),
        ("args.policy=td4", "policy"),
    ] {
        let (code, err) = launch_with_set("uav/encounter.toml", "10s", set);
        assert_ne!(code, 0, "{set}: {err}");
        assert!(err.contains(key), "{set}: {err}");
    }
}

#[test]
fn a_gymnasium_agent_plays_episodes_through_the_bridge() {
    // The first run installs gymnasium into .venv-gym.
    let run = run_scenario("uav", "gym.toml", &["--set", "args.episodes=3"]);
    let u = &run.report["uav"];
    assert_eq!(u["episodes"], 3, "{u}");
    let log = std::fs::read_to_string(run.dir.join("logs/agent.log")).unwrap();
    assert!(log.contains("played 3 episodes"), "{log}");
    // Random increments make it leave its line: every episode records actions.
    assert_eq!(u["metrics"]["action_change"]["n"], 3, "{u}");
    // The report names the Python policy by what it ran.
    assert_eq!(u["policy"], "python random", "{u}");
}

#[test]
fn a_gymnasium_script_declaring_its_params_is_refused_before_the_start_on_a_key_it_lacks() {
    // gym.toml passes `policy`; a script of one's own that declares only `steps` (through
    // CaravanEnv's `params`, read before the node joins) stops the launch in the check before
    // anything starts, naming the key, and runs once the launch replaces the params table.
    let dir = std::env::temp_dir().join(caravan_tests::unique_group("gym-script"));
    std::fs::create_dir_all(&dir).unwrap();
    let script = dir.join("mine.py");
    std::fs::write(
        &script,
        "from caravan import main\n\
         from caravan.gym_env import CaravanEnv, GroupEnded\n\
         def agent():\n\
         \x20   env = CaravanEnv(params={'steps': 5})\n\
         \x20   try:\n\
         \x20       while True:\n\
         \x20           env.reset()\n\
         \x20           done = False\n\
         \x20           while not done:\n\
         \x20               _, _, t, u, _ = env.step(env.action_space.sample())\n\
         \x20               done = t or u\n\
         \x20   except GroupEnded:\n\
         \x20       print('steps param', env.p.steps)\n\
         \x20   finally:\n\
         \x20       env.close()\n\
         main(agent)\n",
    )
    .unwrap();
    let exec = format!(
        "process.agent.exec='../../python/caravan-python --venv gym --requirements uav/requirements-gym.txt {}'",
        script.display()
    );
    let (code, err) = launch_with_sets("uav/gym.toml", "100000s", &[&exec]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("policy") && !err.contains("Traceback"),
        "{err}"
    );
    let run = run_scenario(
        "uav",
        "gym.toml",
        &[
            "--set",
            &exec,
            "--set",
            "process.agent.params={ steps = 7 }",
            "--set",
            "args.episodes=1",
            "--set",
            "args.label=mine",
        ],
    );
    let log = std::fs::read_to_string(run.dir.join("logs/agent.log")).unwrap();
    assert!(log.contains("steps param 7"), "{log}");
    assert_eq!(run.report["uav"]["policy"], "mine");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_shipped_learned_policy_passes_in_the_agent_process() {
    // TD3 trained on the head-on scenario only (launch/uav/train.toml), run by the Rust agent
    // from its JSON weights, against shifted straight opponents.
    let u = uav("mlp", "s1", 6);
    assert_eq!(u["outcomes"]["passed"]["count"], 6, "{u}");
}

#[path = "ranges/refused.rs"]
mod refused;
#[path = "ranges/uav_convoy.rs"]
mod uav_convoy_ranges;
