"""A Gymnasium environment over a running Caravan group.

The group holds the environment as processes (physics, an environment process that runs the
episodes, scripted opponents…) and speaks Gymnasium's protocol on three topics:
``agent/observation`` (``EnvStep``: observation, reward, terminated, truncated; step 0 is the
reset), ``agent/action`` (``AgentAction``) and ``agent/episode`` (``EpisodeEnd``). The UAV
scenario declares those messages (crate ``caravan-uav``, ``messages.rs``); their descriptors and
topics come with this package as ``uav_messages.json``, which a test keeps equal to the Rust
declaration, and the classes are built from them (``caravan.types``). This module is
the agent's side: a ``gymnasium.Env`` whose ``reset`` and ``step`` exchange those messages, so a
standard RL library (Stable-Baselines3, SBX…) trains against the group as it would against any
environment. It needs the ``gymnasium`` package (``python/uav/requirements-gym.txt``).

The node runs on a thread of its own: each observation it receives waits there until the
learner's next ``step`` supplies the action, so in lockstep the whole group waits for the
learner and runs are reproducible. The node and its ports live on that thread (iceoryx2's
ports stay on the thread that made them). Run the learner as the group's agent process::

    env = CaravanEnv(action="continuous", params={"steps": 10000})
    p = env.p                               # the launch file's params for this process
    model.learn(total_timesteps=p.steps)    # calls env.reset() and env.step(a)
    env.close()                             # the node leaves the group

``params`` declares the process's params (names and defaults): they are read before the node
joins, so the launcher's check before start refuses an unknown or mistyped key and nothing
starts. The launch file's params must match: ``launch/uav/gym.toml`` passes ``policy``, so a
script run in its place declares ``policy`` too, or the launch replaces the params
(``--set 'process.agent.params={}'``).
"""

from __future__ import annotations

import json
import queue
import threading
from pathlib import Path
from typing import Any, Optional

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from .identity import Identity, parse_params
from .node import Node
from .schemas import fixed_vec, set_fixed_vec
from .types import message_class

_MESSAGES = json.loads(Path(__file__).with_name("uav_messages.json").read_text())
EnvStep, AgentAction, EpisodeEnd = (message_class(d) for d in _MESSAGES["types"])
AGENT_OBSERVATION = _MESSAGES["topics"]["AGENT_OBSERVATION"]
AGENT_ACTION = _MESSAGES["topics"]["AGENT_ACTION"]
AGENT_EPISODE = _MESSAGES["topics"]["AGENT_EPISODE"]


class GroupEnded(RuntimeError):
    """The group stopped while the learner waited for an observation."""


class CaravanEnv(gym.Env):
    """The group's episodic environment as a ``gymnasium.Env``.

    ``action`` is ``"continuous"`` (a Box of ``action_size`` numbers in [-1, 1]) or
    ``"discrete"`` (``n_actions`` choices); observations are a Box of ``observation_size``
    numbers in [-1, 1]."""

    metadata = {"render_modes": []}

    def __init__(
        self,
        action: str = "continuous",
        observation_size: int = 6,
        action_size: int = 2,
        n_actions: int = 9,
        params: Optional[dict] = None,
    ) -> None:
        super().__init__()
        if action not in ("continuous", "discrete"):
            raise ValueError(f"action must be 'continuous' or 'discrete', got {action!r}")
        # Params first: in the launcher's check before start, the node's thread ends at its
        # first port, so a key read after that would be checked only once the group runs.
        self.p = None
        if params is not None:
            identity = Identity.from_env()
            self.p = parse_params(identity.name, identity.params, params)
        self.continuous = action == "continuous"
        self.observation_space = spaces.Box(-1.0, 1.0, (observation_size,), np.float32)
        self.action_space = (
            spaces.Box(-1.0, 1.0, (action_size,), np.float32)
            if self.continuous
            else spaces.Discrete(n_actions)
        )
        self._steps: "queue.Queue[Optional[Any]]" = queue.Queue()
        self._actions: "queue.Queue[Optional[Any]]" = queue.Queue(maxsize=1)
        self._ready = threading.Event()
        self._failure: Optional[BaseException] = None
        self.node: Optional[Node] = None
        self._thread = threading.Thread(target=self._serve, name="caravan-node", daemon=True)
        self._thread.start()
        self._ready.wait()
        if self._failure is not None:
            raise self._failure
        self.episode = 0

    def params(self, defaults: dict):
        """This process's params from the launch file, over ``defaults`` (see ``Node.params``).
        Read once the node has joined: prefer ``CaravanEnv(params=defaults)``, which the
        launcher's check before start covers."""
        return self.node.params(defaults)

    # -- the node's thread --------------------------------------------------------------------

    def _serve(self) -> None:
        try:
            node = Node.from_env()
            observations = node.subscriber(EnvStep, AGENT_OBSERVATION)
            publisher = node.publisher(AgentAction, AGENT_ACTION)
        except BaseException as e:  # reported by the constructor
            self._failure = e
            self._ready.set()
            return
        self.node = node
        self._ready.set()

        def step(s) -> None:
            for m in observations.receive_all():
                e = m.payload
                self._steps.put(e)
                if e.terminated or e.truncated:
                    continue
                action = self._actions.get()
                if action is None:
                    s.stop()
                    return
                a = AgentAction(episode=e.episode, step=e.step)
                if self.continuous:
                    a.discrete = -1
                    set_fixed_vec(a, "continuous", [float(x) for x in np.ravel(action)])
                else:
                    a.discrete = int(action)
                publisher.publish(a)

        try:
            node.run(step, on=AGENT_OBSERVATION)
        finally:
            self._steps.put(None)

    # -- the learner's side ---------------------------------------------------------------------

    def _next(self) -> Any:
        e = self._steps.get()
        if e is None:
            raise GroupEnded("the Caravan group ended")
        return e

    @staticmethod
    def _observation(e: Any) -> np.ndarray:
        return np.asarray(fixed_vec(e, "observation"), dtype=np.float32)

    def reset(self, *, seed: Optional[int] = None, options: Optional[dict] = None):
        """The next episode's first observation. The group draws its starts from its own seed
        (the launch file's), so ``seed`` only seeds this object's spaces."""
        super().reset(seed=seed)
        e = self._next()
        while e.step != 0:
            e = self._next()
        self.episode = e.episode
        return self._observation(e), {"episode_number": e.episode}

    def step(self, action):
        self._actions.put(action)
        e = self._next()
        info = {"episode_number": e.episode, "step": e.step}
        return self._observation(e), float(e.reward), bool(e.terminated), bool(e.truncated), info

    def close(self) -> None:
        """Stops answering: the node leaves the group at its next observation."""
        try:
            self._actions.put_nowait(None)
        except queue.Full:
            pass
        self._thread.join(timeout=5.0)
