"""A Gymnasium agent of the UAV encounter (launch/uav/gym.toml): it joins the group through
``caravan.gym_env.CaravanEnv`` and plays episodes with a random policy (the Gymnasium bridge's
smoke test) or a trained policy file (a small MLP in JSON, run with numpy), until the group
ends. The same loop is what an RL library drives when it trains.

Params: ``policy`` ("random" or a JSON weights file relative to the launch file), ``action``
("continuous" or "discrete"), ``seed``.
"""

import json

import numpy as np

from caravan import BadInput, main
from caravan.gym_env import CaravanEnv, GroupEnded
from caravan.identity import Identity, parse_params

PARAMS = {"policy": "random", "action": "continuous", "seed": 0}


def mlp(path):
    """The actor of a weights file: ``{"layers": [{"weight": [[…]], "bias": […]}, …]}``, ReLU
    between layers and tanh on the output, as TD3's actor."""
    try:
        with open(path) as f:
            layers = [
                (np.asarray(l["weight"], dtype=np.float64), np.asarray(l["bias"], dtype=np.float64))
                for l in json.load(f)["layers"]
            ]
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise BadInput(f"key 'policy': cannot read the weights file {path}: {e}")

    def act(obs):
        x = np.asarray(obs, dtype=np.float64)
        for k, (w, b) in enumerate(layers):
            x = w @ x + b
            x = np.tanh(x) if k == len(layers) - 1 else np.maximum(x, 0.0)
        return x

    return act


def agent():
    identity = Identity.from_env()
    p = parse_params(identity.name, identity.params, PARAMS)
    if p.action not in ("continuous", "discrete"):
        raise BadInput(f"key 'action': 'continuous' or 'discrete', got {p.action!r}")
    policy = None if p.policy == "random" else mlp(identity.resolve_path(p.policy))
    env = CaravanEnv(action=p.action)
    env.action_space.seed(p.seed)
    episodes = 0
    try:
        while True:
            obs, _ = env.reset()
            done = False
            while not done:
                a = env.action_space.sample() if policy is None else policy(obs)
                obs, _, terminated, truncated, _ = env.step(a)
                done = terminated or truncated
            episodes += 1
    except GroupEnded:
        print(f"played {episodes} episodes")
    finally:
        env.close()


if __name__ == "__main__":
    main(agent)
