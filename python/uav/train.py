"""Trains a policy for the UAV encounter inside Caravan (launch/uav/train.toml): the learner is
the group's agent process and reaches the environment through ``caravan.gym_env.CaravanEnv``,
so every training step runs the real group (physics, environment, opponent) in lockstep.

SBX (Stable-Baselines in JAX, by the Stable-Baselines3 authors) trains TD3 (or SAC) on the
fixed head-on scenario; the actor is written to ``out`` as a small JSON MLP (ReLU hidden
layers, tanh output) that the Rust agent (`caravan-uav-agent`, policy = "mlp") and
``gym_agent.py`` run without any training package, and every episode's return and outcome to
``curve`` (CSV) for the learning curve. Needs python/uav/requirements-train.txt (installed
into .venv-train on first use; not in CI).
"""

import csv
import json
import os
import time

import gymnasium
import numpy as np

from caravan import BadInput, main
from caravan.gym_env import CaravanEnv, GroupEnded
from caravan.identity import Identity, parse_params

PARAMS = {
    "algorithm": "td3",
    "steps": 30000,
    "seed": 1,
    "out": "policies/td3.json",
    "curve": "policies/td3-curve.csv",
    "hidden": 64,
    "learning_starts": 1000,
}


class Curve(gymnasium.Wrapper):
    """Wraps the environment to log every episode: number, step count, return, outcome, time."""

    def __init__(self, env, path):
        super().__init__(env)
        self.path = path
        self.rows, self.ret, self.length = [], 0.0, 0
        self.started = time.time()
        self.total_steps = 0

    def reset(self, **kwargs):
        self.ret, self.length = 0.0, 0
        return self.env.reset(**kwargs)

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        self.ret += reward
        self.length += 1
        self.total_steps += 1
        if terminated or truncated:
            outcome = "timeout" if truncated else ("passed" if reward > 0 else "collided")
            self.rows.append(
                (len(self.rows) + 1, self.total_steps, self.length, round(self.ret, 3), outcome,
                 round(time.time() - self.started, 1))
            )
        return obs, reward, terminated, truncated, info

    def save(self):
        os.makedirs(os.path.dirname(self.path) or ".", exist_ok=True)
        with open(self.path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["episode", "total_steps", "steps", "return", "outcome", "wall_s"])
            w.writerows(self.rows)


def export_actor(model, path):
    """The actor's dense layers as {"layers": [{"weight": out×in, "bias": out}, …]}."""
    params = model.policy.actor_state.params
    dense = params["params"] if "params" in params else params
    layers = []

    def walk(tree):
        if isinstance(tree, dict) and "kernel" in tree and "bias" in tree:
            layers.append(tree)
            return
        if isinstance(tree, dict):
            for key in sorted(tree, key=lambda k: (len(k), k)):
                walk(tree[key])

    walk(dense)
    out = {
        "algorithm": type(model).__name__,
        "hidden_activation": "relu",
        "output_activation": "tanh",
        "layers": [
            {"weight": np.asarray(l["kernel"]).T.tolist(), "bias": np.asarray(l["bias"]).tolist()}
            for l in layers
        ],
    }
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    with open(path, "w") as f:
        json.dump(out, f)


def agent():
    identity = Identity.from_env()
    p = parse_params(identity.name, identity.params, PARAMS)
    try:
        from sbx import SAC, TD3
    except ImportError as e:
        raise BadInput(f"the training packages are missing ({e}); see python/uav/requirements-train.txt")
    algorithms = {"td3": TD3, "sac": SAC}
    if p.algorithm not in algorithms:
        raise BadInput(f"key 'algorithm': one of {sorted(algorithms)}, got {p.algorithm!r}")
    env = CaravanEnv(action="continuous")
    logged = Curve(env, identity.resolve_path(p.curve))
    model = algorithms[p.algorithm](
        "MlpPolicy",
        logged,
        seed=p.seed,
        learning_starts=p.learning_starts,
        policy_kwargs={"net_arch": [p.hidden, p.hidden]},
        verbose=0,
    )
    started = time.time()
    try:
        model.learn(total_timesteps=p.steps)
    except GroupEnded:
        print("the group ended before training did")
    finally:
        logged.save()
        export_actor(model, identity.resolve_path(p.out))
        passed = sum(1 for r in logged.rows[-50:] if r[4] == "passed")
        print(
            f"trained {p.algorithm} for {logged.total_steps} steps ({len(logged.rows)} episodes) "
            f"in {time.time() - started:.0f} s; last 50 episodes passed: {passed}"
        )
        env.close()


if __name__ == "__main__":
    main(agent)
