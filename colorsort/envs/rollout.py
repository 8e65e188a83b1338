"""The one episode loop: an actor drives an env until the episode ends; observers watch every step.

Recording (``data/recorder.py``), evaluation (``benchmark/evaluate.py``), DAgger's take-overs
(``training/takeover.py``) and ``colorsort-sort`` (``benchmark/sorting.py``) run their episodes through
``rollout``. What differs between them is an ``Observer``: the dataset writer and its timer, the film, the sorting
log, DAgger's labels. A shift, a timer or a film added here reaches all four.

The env is seen through ``EpisodeEnv``: ``CellEpisode`` for the robosuite cell (an episode ends when its boxes
have left the belt or at a time limit), ``GymEpisode`` for the Gymnasium env (``terminated or truncated``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from colorsort.envs.robosuite_task import ColorSort


@dataclass(frozen=True)
class Step:
    """One control step's actions: ``stored`` is what a dataset labels it with, ``executed`` what the env is given
    (the same, unless a demonstrator's perturbation holds something back)."""

    stored: np.ndarray
    executed: np.ndarray


class Observer:
    """Watches an episode. Every hook is a no-op here: an observer writes the ones it needs."""

    def on_start(self, obs: Any) -> None:
        """The episode's first observation, before any step."""

    def on_observe(self, obs: Any) -> None:
        """Before the actor is asked for this step's action."""

    def on_action(self, obs: Any, step: Step) -> None:
        """The actor's step for ``obs``, before the env takes it."""

    def on_step(self, obs: Any, info: dict) -> None:
        """The env took the step: the new observation and its info."""


class EpisodeEnv(Protocol):
    """An env as the loop steps it."""

    @property
    def ended(self) -> bool: ...

    def step(self, action: np.ndarray) -> tuple[Any, dict]: ...


class CellEpisode:
    """The robosuite cell: an episode ends when ``boxes`` boxes have left the belt, or at ``limit`` [s] of sim time."""

    def __init__(self, env: ColorSort, boxes: int, limit: float):
        self.env, self.boxes, self.limit = env, boxes, limit

    @property
    def ended(self) -> bool:
        return len(self.env.events) >= self.boxes or self.env.cur_time >= self.limit

    def step(self, action: np.ndarray) -> tuple[Any, dict]:
        obs, _, _, info = self.env.step(action)
        return obs, info


class GymEpisode:
    """A Gymnasium env just reset: an episode ends when a step says ``terminated`` or ``truncated``."""

    def __init__(self, env: Any):
        self.env, self.ended = env, False

    def step(self, action: np.ndarray) -> tuple[Any, dict]:
        obs, _, terminated, truncated, info = self.env.step(action)
        self.ended = bool(terminated or truncated)
        return obs, info


class Stopped(Exception):
    """The loop was asked to stop (``rollout``'s ``stop``) before the episode ended."""


@dataclass(frozen=True)
class Ending:
    """How a rollout ended: the last observation and info, the steps taken, and whether the episode ended
    (False: ``max_steps`` came first)."""

    obs: Any
    info: dict
    steps: int
    ended: bool


def rollout(env: EpisodeEnv, obs: Any, actor: Callable[[Any], np.ndarray | Step],
            observers: Sequence[Observer] = (), *, max_steps: int | None = None,
            stop: Callable[[], bool] | None = None) -> Ending:
    """Step ``env`` from ``obs`` with ``actor``'s actions until the episode ends (or ``max_steps`` steps), each
    observer told of each step in order. An actor gives an action, or a ``Step`` whose ``executed`` action the
    env takes. ``stop()`` turning true raises ``Stopped`` before the next step."""
    for o in observers:
        o.on_start(obs)
    info: dict = {}
    steps = 0
    while not env.ended and (max_steps is None or steps < max_steps):
        if stop is not None and stop():
            raise Stopped
        for o in observers:
            o.on_observe(obs)
        given = actor(obs)
        step = given if isinstance(given, Step) else Step(given, given)
        for o in observers:
            o.on_action(obs, step)
        obs, info = env.step(step.executed)
        steps += 1
        for o in observers:
            o.on_step(obs, info)
    return Ending(obs, info, steps, env.ended)
