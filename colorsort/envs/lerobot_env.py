"""LeRobot's ``EnvConfig`` for ColorSort, so that LeRobot's own tools evaluate policies on it.

LeRobot 0.6 finds it by itself: ``make install`` (or ``pip install plugins/lerobot_env_colorsort``)
installs the plugin distribution ``lerobot_env_colorsort``, which LeRobot's CLIs import at start
(``register_third_party_plugins``). ``--env.discover_packages_path=colorsort`` works too::

    lerobot-eval --env.type=colorsort --env.task=ColorSort-Jitter-v0 \\
        --policy.path=outputs/train/act/checkpoints/last/pretrained_model --policy.device=cpu \\
        --eval.n_episodes=10 --eval.batch_size=2

``--env.task`` is a Gymnasium id without the ``colorsort/`` namespace (``ColorSort-v0`` or a
variant's, see ``colorsort-eval --list``); ``--env.cameras`` and ``--env.image_size`` must match
the dataset the policy was trained on (``--env.cameras=none`` for a state-only policy).
``--env.shift=camera-pose:2`` (comma-separated ``NAME:LEVEL``, docs/shifts.md) evaluates under held-out shifts;
``--env.backend=warp`` runs the ``--eval.batch_size`` envs as one batched cell on MuJoCo Warp
(``--env.device``, cuda:0 by default; the ``gpu`` extra; docs/gpu.md).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import draccus
from draccus.utils import DecodingError
from lerobot.configs.types import FeatureType, PolicyFeature
from lerobot.envs.configs import EnvConfig
from lerobot.utils.constants import ACTION, OBS_ENV_STATE, OBS_IMAGES, OBS_STATE

from colorsort.cell.cameras import DEFAULT_CAMERAS, DEFAULT_IMAGE_SIZE, parse_cameras
from colorsort.config import BACKENDS
from colorsort.envs.schema import ENV_STATE_SIZE, state_size
from colorsort.errors import ConfigError, UnknownName
from colorsort.robots import ROBOTS
from colorsort.shifts import parse_shifts
from colorsort.variants import Variant, get_variant, gym_ids

NAMESPACE = "colorsort"


class Checked(str):
    """A text flag of ``ColorSortEnv`` that draccus checks as it decodes it (``check`` raises ``ConfigError``
    naming the valid values), so that ``lerobot-eval``'s error ends in that line, not in draccus's "Couldn't
    instantiate class"."""

    @staticmethod
    def check(text: str) -> None:
        raise NotImplementedError


class TaskName(Checked):
    """``--env.task``: a Gymnasium id without its namespace."""

    @staticmethod
    def check(text: str) -> None:
        variant_of_task(text)


class BackendName(Checked):
    """``--env.backend``: one of ``BACKENDS``."""

    @staticmethod
    def check(text: str) -> None:
        if text not in BACKENDS:
            raise ConfigError(f"--env.backend={text!r}; valid backends: {list(BACKENDS)}")


class ShiftText(Checked):
    """``--env.shift``: held-out shifts, comma-separated ``NAME:LEVEL``."""

    @staticmethod
    def check(text: str) -> None:
        parse_shifts(text)


def _decode_checked[T: Checked](cls: type[T]) -> Callable[[Any, Sequence[str]], T]:
    def decode(raw_value: Any, path: Sequence[str]) -> T:
        text = str(raw_value)
        try:
            cls.check(text)
        except ConfigError as err:
            raise DecodingError(path, str(err)) from None
        return cls(text)
    return decode


for _checked in (TaskName, BackendName, ShiftText):  # draccus's decoder registry: its public way to a custom type
    draccus.decode.register(_checked, _decode_checked(_checked))


def variant_of_task(task: str) -> Variant:
    """The benchmark variant behind a Gymnasium id without its namespace, e.g. ``ColorSort-Jitter-v0``."""
    ids = gym_ids()
    gym_id = f"{NAMESPACE}/{task}"
    if gym_id not in ids:
        valid = sorted(i.removeprefix(f"{NAMESPACE}/") for i in ids)
        raise UnknownName("ColorSort task", task, valid, "tasks")
    return get_variant(ids[gym_id])


@EnvConfig.register_subclass("colorsort")
@dataclass
class ColorSortEnv(EnvConfig):
    """ColorSort for LeRobot: ``task`` is the Gymnasium id without its namespace."""

    task: TaskName = TaskName("ColorSort-v0")  # LeRobot's field is str | None: a task is always named
    fps: int = 20  # control rate [Hz], as recorded
    cameras: str = ",".join(DEFAULT_CAMERAS)  # comma-separated, as colorsort-collect --cameras records; "none"
    image_size: int = DEFAULT_IMAGE_SIZE[0]  # square camera images [px]
    episode_length: int | None = None  # steps before truncation; default: the variant's time limit
    backend: BackendName = BackendName("cpu")  # "cpu": one ColorSortGymEnv per env; "warp": one batched cell
    device: str = "cuda:0"  # the batched cell's Warp device (backend warp): cuda:0, or cpu
    shift: ShiftText = ShiftText("")  # held-out shifts, comma-separated NAME:LEVEL (docs/shifts.md); "" for none
    features: dict[str, PolicyFeature] = field(default_factory=dict)
    features_map: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.task is None:
            raise ConfigError("--env.task: give a ColorSort task, e.g. ColorSort-Default-v0 (colorsort-eval --list)")
        BackendName.check(self.backend)  # as draccus checks them (from Python: the same ConfigError)
        ShiftText.check(self.shift)
        variant = variant_of_task(self.task)
        n = ROBOTS[variant.robot].n_joints
        self.features = {
            ACTION: PolicyFeature(type=FeatureType.ACTION, shape=(n + 2,)),
            "agent_pos": PolicyFeature(type=FeatureType.STATE, shape=(state_size(n, variant.task_config.tracking),)),
            "environment_state": PolicyFeature(type=FeatureType.ENV, shape=(ENV_STATE_SIZE,)),
        }
        self.features_map = {ACTION: ACTION, "agent_pos": OBS_STATE, "environment_state": OBS_ENV_STATE}
        # Cameras under the policy's own key, not LeRobot's usual "pixels/<camera>": lerobot-eval's
        # --eval.recording=true makes a dataset feature of each env feature, and those may not hold "/".
        for cam in self.camera_list:
            key = f"{OBS_IMAGES}.{cam}"
            self.features[key] = PolicyFeature(type=FeatureType.VISUAL, shape=(self.image_size, self.image_size, 3))
            self.features_map[key] = key

    @property
    def camera_list(self) -> tuple[str, ...]:
        return parse_cameras(self.cameras)

    @property
    def package_name(self) -> str:
        return "colorsort"

    @property
    def gym_id(self) -> str:
        return f"{NAMESPACE}/{self.task}"

    def create_envs(self, n_envs: int, use_async_envs: bool = False) -> dict:
        """LeRobot's ``{suite: {task index: VectorEnv}}``; with ``backend`` warp, one batched cell of ``n_envs``."""
        if self.backend == "cpu":
            return super().create_envs(n_envs, use_async_envs)
        import gymnasium as gym

        env = gym.make_vec(self.gym_id, num_envs=n_envs, vectorization_mode="vector_entry_point", device=self.device,
                           render_mode="rgb_array", **self.gym_kwargs)  # the registry's entry point: no import here
        return {NAMESPACE: {0: env}}

    @property
    def gym_kwargs(self) -> dict:
        kwargs = {"cameras": self.camera_list, "image_size": (self.image_size, self.image_size), "fps": self.fps,
                  "episode_length": self.episode_length}
        return {**kwargs, "shift": self.shift} if self.shift else kwargs
