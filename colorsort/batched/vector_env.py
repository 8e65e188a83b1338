"""The batched cell as a Gymnasium vector env: ``num_envs`` ColorSort envs stepped as one, on a Warp device.

Observations, actions, rewards and ``info`` are those of ``num_envs`` ``ColorSortGymEnv`` (numpy, the same
spaces), so code written for ``gymnasium.vector.SyncVectorEnv`` over ColorSort runs on it unchanged::

    import gymnasium as gym, colorsort
    envs = gym.make_vec("colorsort/ColorSort-v0", num_envs=1024, vectorization_mode="vector_entry_point",
                        device="cuda:0")

An episode ends as on the CPU cell; a finished env is reset in the same step (Gymnasium's ``SAME_STEP``
autoreset: the step returns the new episode's first observation, the last one under ``info["final_obs"]``
and the finished episode's ``info`` under ``info["final_info"]``), with the next seed of its own sequence
(the reset's seed + env index, then + ``num_envs`` each time).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from colorsort.batched.cell import BatchedCell, StepResult
from colorsort.batched.evaluate import tally
from colorsort.batched.spec import CellSpec, spec_for_variant
from colorsort.cell.cameras import DEFAULT_IMAGE_SIZE
from colorsort.cell.referee import Outcome
from colorsort.envs.gym_env import ColorSortGymEnv
from colorsort.errors import ConfigError
from colorsort.shifts import parse_shifts
from colorsort.variants import Variant, get_variant


def refuse_shifts(shift: str | Iterable[str] | None) -> None:
    """ValueError for any held-out shift above level 0: the batched cell applies none yet (``docs/shifts.md``)."""
    active = [str(s) for s in parse_shifts(shift) if s.active]
    if active:
        raise ConfigError(f"the batched cell (MuJoCo Warp) applies no held-out shift yet; asked: {', '.join(active)}. "
                          "Run shifts on the CPU cell: gym.make(id, shift=...), colorsort-eval --backend cpu")


class BatchedVectorEnv(gym.vector.VectorEnv):
    """``num_envs`` envs of one variant on the batched cell.

    Args:
        variant: a variant name or ``Variant``.
        num_envs: worlds stepped together.
        device: Warp's device ("cpu" or "cuda:0").
        cameras, image_size: as ``ColorSortGymEnv``'s (none by default: state only).
        episode_length: steps before truncation; default: the variant's time limit.
        render_mode: "rgb_array" (``render`` gives every env's scene camera at ``image_size``) or None.
        fps: the control rate [Hz]; the batched cell runs at the CPU cell's default, 20.
        shift: held-out shifts: any above level 0 is refused (the batched cell applies none yet).
        spec: the variant's cell, if already built (``CellSpec``).
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_fps": 20}

    def __init__(self, variant: str | Variant = "default", num_envs: int = 8, device: str = "cpu",
                 cameras: tuple[str, ...] = (), image_size: tuple[int, int] = DEFAULT_IMAGE_SIZE,
                 episode_length: int | None = None, render_mode: str | None = None, spec: CellSpec | None = None,
                 fps: int = 20, shift: str | Iterable[str] | None = None):
        refuse_shifts(shift)
        self.variant = get_variant(variant) if isinstance(variant, str) else variant
        single = ColorSortGymEnv(self.variant, cameras=tuple(cameras), image_size=(image_size[0], image_size[1]),
                                 render_mode=None,
                                 episode_length=episode_length)  # its spaces; it builds no simulation
        self.num_envs = num_envs
        self.single_observation_space = single.observation_space
        self.single_action_space = single.action_space
        self.observation_space = batch_space(single.observation_space, num_envs)
        self.action_space = batch_space(single.action_space, num_envs)
        self._max_episode_steps = single.max_episode_steps
        self.task_description = single.task_description
        self.cameras = tuple(cameras)
        self.render_mode = render_mode
        rendered = self.cameras + (("scene",) if render_mode == "rgb_array" and "scene" not in self.cameras else ())
        spec = spec or spec_for_variant(self.variant.name)
        if fps != spec.control_freq:
            raise ConfigError(f"fps={fps}: the batched cell steps at the CPU cell's {spec.control_freq:.0f} Hz")
        spawns = int(np.ceil(self._max_episode_steps / spec.control_freq / self.variant.task_config.spawn_period)) + 2
        self.cell = BatchedCell(spec, self.variant, num_envs, device=device,
                                max_boxes=max(self.variant.boxes + 2, spawns), cameras=rendered,
                                image_size=(image_size[0], image_size[1]))
        self.steps = np.zeros(num_envs, int)
        self._seeds: np.ndarray = np.zeros(num_envs, np.int64)

    def reset(self, *, seed: int | list[int] | None = None, options: dict | None = None):
        """Every env's new episode; ``seed`` + i for env i (or a seed per env; None: drawn)."""
        super().reset(seed=seed if isinstance(seed, int) else None)
        if seed is None:
            self._seeds = self.np_random.integers(2**31, size=self.num_envs).astype(np.int64)
        elif isinstance(seed, int):
            self._seeds = np.arange(self.num_envs, dtype=np.int64) + seed
        else:
            self._seeds = np.asarray(seed, np.int64)
        self.steps[:] = 0
        out = self.cell.reset(self._seeds)
        return self._observation(out), self._info()[0]

    def step(self, actions):
        actions = np.asarray(actions, np.float32)
        out = self.cell.step(actions)
        self.steps += 1
        info, terminated = self._info()
        truncated = ~terminated & (self.steps >= self._max_episode_steps)
        obs = self._observation(out)
        reward = out.reward.cpu().numpy().astype(np.float64)
        done = terminated | truncated
        if done.any():
            worlds = np.flatnonzero(done)
            info = {**info, "final_obs": obs, "final_info": info, "_final_obs": done, "_final_info": done}
            self._seeds[worlds] += self.num_envs
            self.steps[worlds] = 0
            out = self.cell.reset(self._seeds[worlds], worlds=worlds)
            obs = self._observation(out)
        return obs, reward, terminated, truncated, info

    def render(self) -> tuple | None:
        """Every env's scene camera now, (H, W, 3) uint8 each (with ``render_mode="rgb_array"``)."""
        if self.render_mode != "rgb_array":
            return None
        return tuple(self.cell.images["scene"].cpu().numpy())

    def call(self, name: str, *args: Any, **kwargs: Any) -> tuple:
        """An attribute (or a method's result) of every env, as ``SyncVectorEnv.call`` gives it."""
        if name == "render":
            return self.render() or (None,) * self.num_envs
        value = getattr(self, name)
        value = value(*args, **kwargs) if callable(value) else value
        return tuple(value for _ in range(self.num_envs))

    def get_attr(self, name: str) -> tuple:
        """An attribute of every env (``SyncVectorEnv.get_attr``)."""
        return tuple(getattr(self, name) for _ in range(self.num_envs))

    def close_extras(self, **kwargs: Any) -> None:
        self.cell = None  # type: ignore[assignment]

    def _observation(self, out: StepResult) -> dict:
        obs: dict[str, Any] = {"agent_pos": out.state.cpu().numpy().copy(),
                               "environment_state": out.env_state.cpu().numpy().copy()}
        if self.cameras:
            obs = {"pixels": {c: out.images[c].cpu().numpy() for c in self.cameras}, **obs}
        return obs

    def _info(self) -> tuple[dict[str, np.ndarray], np.ndarray]:
        """``ColorSortGymEnv``'s counters, one row per env (the first ``variant.boxes`` boxes of each episode), and
        which episodes ended (``referee.episode_rule``)."""
        n_events = self.cell.n_events.numpy()
        t = tally(n_events, self.cell.ev_outcome.numpy(), self.variant.boxes)
        return {"is_success": t["success"], "failed": t["failed"], "correct": t[Outcome.PLACED.value],
                "misplaced": t[Outcome.MISPLACED.value], "dropped": t[Outcome.DROPPED.value],
                "let_through": t[Outcome.REJECTED.value], "boxes_done": np.minimum(n_events, self.variant.boxes),
                "sim_time": self.steps / self.cell.spec.control_freq}, t["terminated"]
