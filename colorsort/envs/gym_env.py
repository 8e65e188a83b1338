"""ColorSort as a Gymnasium env with LeRobot's conventions for simulated tasks.

``import colorsort`` registers ``colorsort/ColorSort-v0`` (the ``default`` variant) and one id
per variant (``colorsort.variants``)::

    import gymnasium as gym, colorsort
    env = gym.make("colorsort/ColorSort-Jitter-v0", cameras=("scene", "wrist"), image_size=(128, 128))
    obs, info = env.reset(seed=0)   # obs["pixels"]["scene"]: (128, 128, 3) uint8
                                    # obs["agent_pos"]: (23,); (24,) on a tracking belt

Observations: ``pixels`` (a dict of camera images, (H, W, 3) uint8), ``agent_pos``
(``observation.state`` of the datasets) and ``environment_state`` (the next box: colour one-hot,
pose). Actions: the datasets' ``action`` (joint targets [rad], suction, belt pass), float32.
Reward: +1 per box in its colour's bin, -1 per box misplaced or dropped. An episode terminates
when the variant's number of boxes has left the belt (``info["is_success"]`` when each went where
it belongs) or at the first box misplaced or dropped; it is truncated at the variant's step limit.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from colorsort.cell.cameras import DEFAULT_CAMERAS, DEFAULT_IMAGE_SIZE, check_cameras
from colorsort.cell.referee import EpisodeTally, Outcome, episode_rule
from colorsort.envs.robosuite_task import ColorSort
from colorsort.envs.schema import ENV_STATE_SIZE, box_state, robot_state, state_size
from colorsort.errors import ConfigError
from colorsort.robots import ROBOTS
from colorsort.shifts import parse_shifts
from colorsort.variants import Variant, get_variant, gym_ids


class ColorSortGymEnv(gym.Env):
    """One variant of the task, as a Gymnasium env.

    The robosuite env (and with it MuJoCo's GL context) is built on the first ``reset``,
    ``step`` or ``render``, in the process that uses it: a vector env's parent process builds
    this object only to read its spaces, and never renders before it forks its workers.

    Args:
        variant: a name from ``colorsort.variants.VARIANTS``, or a ``Variant``.
        cameras: the cameras in ``obs["pixels"]``, any of "scene", "sensor", "wrist"; with none, the
            observation has no ``pixels`` (state only) and nothing renders unless ``render`` is called.
        image_size: (height, width) of every camera [px].
        fps: control rate [Hz].
        render_mode: "rgb_array" (the scene camera at ``image_size``) or None.
        episode_length: truncate after this many steps; default: the variant's time limit.
            (``gym.make(..., max_episode_steps=N)`` adds Gymnasium's own ``TimeLimit`` on top.)
        shift: held-out shifts (``NAME:LEVEL``, a list or one comma-separated string; ``docs/shifts.md``) applied
            by the robosuite env to every episode; nothing of them shows in observations, ``task`` or ``info``.
    """

    action_space: spaces.Box  # joint targets [rad], suction, belt pass

    metadata = {"render_modes": ["rgb_array"], "render_fps": 20}

    def __init__(self, variant: str | Variant = "default", cameras: tuple[str, ...] = DEFAULT_CAMERAS,
                 image_size: tuple[int, int] = DEFAULT_IMAGE_SIZE, fps: int = 20, render_mode: str | None = "rgb_array",
                 episode_length: int | None = None, shift: str | Iterable[str] | None = None):
        self.variant = get_variant(variant) if isinstance(variant, str) else variant
        self.shift = tuple(str(s) for s in parse_shifts(shift))  # validated here, applied by the robosuite env
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"render_mode={render_mode!r}; valid modes: [None, 'rgb_array']")
        check_cameras(cameras)
        if episode_length is not None and episode_length < 1:
            raise ConfigError(f"episode_length={episode_length}: give at least 1 step, or None for the variant's limit")
        self.render_mode = render_mode
        self.cameras = tuple(cameras)
        self.image_size = tuple(image_size)
        self.fps = fps
        h, w = self.image_size
        # LeRobot's evaluator reads ``_max_episode_steps`` (Gymnasium's TimeLimit attribute) through env.call.
        self._max_episode_steps = episode_length or int(np.ceil(self.variant.time_limit * fps))
        self.metadata = {**self.metadata, "render_fps": fps}
        robot = ROBOTS[self.variant.robot]
        obs_spaces: dict[str, spaces.Space] = {
            "agent_pos": spaces.Box(-np.inf, np.inf, (state_size(robot.n_joints, self.variant.task_config.tracking),),
                                    np.float32),
            "environment_state": spaces.Box(-np.inf, np.inf, (ENV_STATE_SIZE,), np.float32),
        }
        if self.cameras:
            obs_spaces = {"pixels": spaces.Dict({c: spaces.Box(0, 255, (h, w, 3), np.uint8) for c in self.cameras}),
                          **obs_spaces}
        self.observation_space = spaces.Dict(obs_spaces)
        low, high = robot.action_bounds()
        self.action_space = spaces.Box(low.astype(np.float32), high.astype(np.float32), dtype=np.float32)
        # What LeRobot's evaluator reads from every env (env.call): the task's name and its instruction
        # for language-conditioned policies.
        self.task = self.variant.name
        self.task_description = (f"Sort the next {self.variant.boxes} boxes from the conveyor into the bins "
                                 "of their colours.")
        self._env: ColorSort | None = None
        self.raw_obs: dict[str, Any] = {}  # the robosuite observation behind the last one returned
        self.steps = 0

    @property
    def max_episode_steps(self) -> int:
        """Steps after which an episode is truncated."""
        return self._max_episode_steps

    @property
    def env(self) -> ColorSort:
        """The robosuite task underneath, built on first use."""
        if self._env is None:
            h, w = self.image_size
            self._env = ColorSort(robots=self.variant.robot, config=self.variant.task_config,
                                  use_camera_obs=bool(self.cameras),
                                  has_offscreen_renderer=bool(self.cameras) or self.render_mode is not None,
                                  camera_names=list(self.cameras) or "scene", camera_heights=h, camera_widths=w,
                                  control_freq=self.fps, ignore_done=True, shift=self.shift)
        return self._env

    def set_shift(self, shift: str | Iterable[str] | None) -> None:
        """Held-out shifts from the next reset on (as the constructor's ``shift``): a sweep's arms in one env."""
        self.shift = tuple(str(s) for s in parse_shifts(shift))
        if self._env is not None:
            self._env.set_shift(self.shift)

    # ------------------------------------------------------------------ gym API
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        episode_seed = int(self.np_random.integers(2**31)) if seed is None else int(seed)
        env = self.env
        self.raw_obs = env.reset(seed=episode_seed, lighting=self.variant.lighting)  # lights only: colours stay
        self.steps = 0
        return self._observation(), self._info()

    def step(self, action: np.ndarray):
        if self._env is None:
            raise gym.error.ResetNeeded("Call reset() before step()")
        self.raw_obs, reward, _, _ = self.env.step(np.asarray(action, dtype=np.float32))
        self.steps += 1
        info = self._info()
        _, terminated = episode_rule(info["boxes_done"] >= self.variant.boxes, info["failed"])
        truncated = not terminated and self.steps >= self._max_episode_steps
        return self._observation(), float(reward), bool(terminated), bool(truncated), info

    def render(self) -> np.ndarray | None:
        if self.render_mode is None:
            return None
        h, w = self.image_size
        if "scene_image" in self.raw_obs:
            return self.raw_obs["scene_image"]
        return self.env.camera_image("scene", w, h)

    def close(self) -> None:
        if self._env is not None:
            self._env.close()
            self._env = None

    # ------------------------------------------------------------------ helpers
    def _observation(self) -> dict[str, Any]:
        obs: dict[str, Any] = {"agent_pos": robot_state(self.env, self.raw_obs),
                               "environment_state": box_state(self.env)}
        if self.cameras:
            obs = {"pixels": {c: self.raw_obs[f"{c}_image"] for c in self.cameras}, **obs}
        return obs

    def _info(self) -> dict[str, Any]:
        tally = EpisodeTally.of(self.env.events, self.variant.boxes)
        count = tally.counts
        return {
            "is_success": tally.verdict.success,
            "failed": tally.verdict.failed,
            "correct": count[Outcome.PLACED],
            "misplaced": count[Outcome.MISPLACED],
            "dropped": count[Outcome.DROPPED],
            "let_through": count[Outcome.REJECTED],
            "distractors": tally.distractors,
            "boxes_done": sum(count.values()),
            "sorted_times": tally.sorted_times,  # [s] boxes handled right
            "sim_time": self.env.cur_time,
        }


def register_envs() -> None:
    """Register ``colorsort/ColorSort-v0`` and every variant's id with Gymnasium (idempotent)."""
    ids = gym_ids()
    for gym_id, name in ids.items():
        if gym_id not in gym.registry:
            # gym.make_vec(id, num_envs=N, vectorization_mode="vector_entry_point", device=...) runs the batched cell
            # (MuJoCo Warp, the gpu extra; imported only then)
            gym.register(id=gym_id, entry_point="colorsort.envs.gym_env:ColorSortGymEnv", kwargs={"variant": name},
                         disable_env_checker=True,
                         vector_entry_point="colorsort.batched.vector_env:BatchedVectorEnv")
