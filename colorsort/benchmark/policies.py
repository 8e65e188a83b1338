"""Policies the evaluation harness runs: the scripted expert, a random policy, a LeRobot checkpoint.

Each takes Gymnasium observations of a ``ColorSortGymEnv`` and returns its action (float32):
``policy.reset(env, seed)`` at the start of every episode, then ``policy.act(obs)`` every step.
"""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from colorsort.envs.gym_env import ColorSortGymEnv
from colorsort.envs.schema import state_size
from colorsort.errors import ConfigError
from colorsort.expert.config import ExpertConfig
from colorsort.robots import get_robot
from colorsort.variants import Variant


class Policy(Protocol):
    name: str

    def reset(self, env: ColorSortGymEnv, seed: int) -> None: ...

    def act(self, obs: dict[str, Any]) -> np.ndarray: ...


class ExpertPolicy:
    """The scripted expert (``expert.factory.make_expert``): it reads the robosuite observation behind ``obs``.
    ``config`` replaces its belt's preset settings (``ExpertConfig``)."""

    name = "expert"

    def __init__(self, config: ExpertConfig | None = None):
        self.config = config

    def reset(self, env: ColorSortGymEnv, seed: int) -> None:
        from colorsort.expert.factory import make_expert

        self.env = env
        if getattr(self, "_for", None) is not env.env:  # the expert's IK and drop points: once per env
            with env.env.shifts.cameras_as_built():  # calibrated where the camera was installed, as a real cell is
                self.expert, self._for = make_expert(env.env, self.config), env.env
        self.expert.reset(env.raw_obs)

    def act(self, obs: dict[str, Any]) -> np.ndarray:
        return self.expert.act(self.env.raw_obs).astype(np.float32)

    @property
    def phase(self) -> str:
        """The expert's phase now (filmed evaluations write it on the frame)."""
        return self.expert.phase.value


class RandomPolicy:
    """Actions drawn uniformly from the action space, from a generator seeded per episode."""

    name = "random"

    def reset(self, env: ColorSortGymEnv, seed: int) -> None:
        self.low = np.asarray(env.action_space.low, dtype=np.float64)
        self.high = np.asarray(env.action_space.high, dtype=np.float64)
        self.rng = np.random.default_rng(seed)

    def act(self, obs: dict[str, Any]) -> np.ndarray:
        return np.asarray(self.rng.uniform(self.low, self.high), dtype=np.float32)


class LeRobotPolicy:
    """A LeRobot checkpoint (``pretrained_model`` folder with its config, weights and processors), on the CPU.

    Its convolutions run in channels-last memory order (1.8x faster for ``act-camera-tracking``'s forward at batch
    1 on these CPUs, ``benchmarks/bench_forward.py``), under ``torch.inference_mode``."""

    def __init__(self, path: str | Path, device: str = "cpu"):
        from lerobot.configs.policies import PreTrainedConfig
        from lerobot.policies.factory import get_policy_class, make_pre_post_processors

        path = Path(path)
        if not (path / "config.json").is_file():
            raise ConfigError(f"{path} is not a LeRobot checkpoint (no config.json); expected e.g. "
                             "outputs/train/<run>/checkpoints/last/pretrained_model")
        self.name = str(path)
        config = PreTrainedConfig.from_pretrained(path)
        config.pretrained_path, config.device = path, device
        with contextlib.redirect_stdout(io.StringIO()):  # LeRobot prints "Loading weights from local directory"
            self.policy = get_policy_class(config.type).from_pretrained(path, config=config)
        self.policy.eval()
        self.channels_last = any(k.startswith("observation.image") for k in config.input_features)
        if self.channels_last:
            import torch

            self.policy.to(memory_format=torch.channels_last)
        skip_unchanged_mode_switches(self.policy)
        self.preprocessor, self.postprocessor = make_pre_post_processors(
            policy_cfg=config, pretrained_path=str(path),
            preprocessor_overrides={"device_processor": {"device": device}})

    def reset(self, env: ColorSortGymEnv, seed: int) -> None:
        import torch

        torch.manual_seed(seed)
        self.task = env.task_description
        self.policy.reset()

    def act(self, obs: dict[str, Any]) -> np.ndarray:
        import torch
        from lerobot.envs.utils import preprocess_observation

        batch = preprocess_observation(obs)
        if self.channels_last:
            batch = {k: v.contiguous(memory_format=torch.channels_last) if v.ndim == 4 else v for k, v in batch.items()}
        batch["task"] = [self.task]
        with torch.inference_mode():
            action = self.postprocessor(self.policy.select_action(self.preprocessor(batch)))
        return action.to("cpu").numpy()[0].astype(np.float32)


def skip_unchanged_mode_switches(module: Any) -> None:
    """Make ``module.eval()`` return at once while ``module`` is in eval mode already.

    LeRobot's ACT calls ``self.eval()`` on every ``select_action`` and every new chunk (a training loop may have
    switched modes between calls); each call sets ``training`` on every submodule through ``nn.Module.__setattr__``
    (measured by hand: `act-camera-snapshot`'s 2 episodes of `default` took 0.89-0.95 times as long with this, 3
    alternating repeats in one process). An evaluation never trains, so a switch that changes no mode is skipped;
    one that does (``train()``) still sets every submodule. The root's mode stands for its submodules': nothing
    here sets a submodule's alone.
    """
    switch = module.train

    def train(mode: bool = True) -> Any:
        return module if mode == module.training else switch(mode)

    module.train = train  # an instance attribute: nn.Module keeps a plain callable in the instance's __dict__


def check_policy_spec(spec: str) -> None:
    """ValueError unless ``spec`` is ``"expert"``, ``"random"`` or a LeRobot checkpoint folder (loads nothing)."""
    if spec in ("expert", "random"):
        return
    if not Path(spec).exists():
        raise ConfigError(f"Unknown policy {spec!r}: give 'expert', 'random' or a LeRobot checkpoint folder")
    if not (Path(spec) / "config.json").is_file():
        raise ConfigError(f"{spec} is not a LeRobot checkpoint (no config.json); expected e.g. "
                         "outputs/train/<run>/checkpoints/last/pretrained_model")


def checkpoint_cameras(path: str | Path) -> tuple[tuple[str, ...], tuple[int, int] | None]:
    """The cameras a LeRobot checkpoint takes (``observation.images.<camera>`` inputs, in order) and their
    (height, width) [px]; ``((), None)`` for a state-only policy. Reads ``config.json`` only."""
    config = json.loads((Path(path) / "config.json").read_text())
    prefix = "observation.images."
    images = {k.removeprefix(prefix): f["shape"] for k, f in config.get("input_features", {}).items()
              if k.startswith(prefix)}
    if not images:
        return (), None
    sizes = {tuple(shape[-2:]) for shape in images.values()}  # (channels, height, width)
    if len(sizes) != 1:
        raise ConfigError(f"{path}: cameras of different sizes {sorted(sizes)}; ColorSort renders one size")
    (size,) = sizes
    return tuple(images), (int(size[0]), int(size[1]))


def misfit(spec: str, variant: Variant) -> str | None:
    """Why a LeRobot checkpoint cannot run on ``variant`` (its state or action sizes differ), or None."""
    if spec in ("expert", "random"):
        return None
    config = json.loads((Path(spec) / "config.json").read_text())
    robot = get_robot(variant.robot)
    wanted = {"observation.state": state_size(robot.n_joints, variant.task_config.tracking),
              "action": len(robot.action_bounds()[0])}
    features = {**config.get("input_features", {}), **config.get("output_features", {})}
    given = {k: f["shape"][0] for k, f in features.items() if k in wanted}
    bad = {k: (given[k], n) for k, n in wanted.items() if k in given and given[k] != n}
    return f"sizes (checkpoint, {variant.name}) differ: {bad}" if bad else None


def make_policy(spec: str) -> Policy:
    """``"expert"``, ``"random"`` or the path of a LeRobot checkpoint."""
    check_policy_spec(spec)
    if spec == "expert":
        return ExpertPolicy()
    if spec == "random":
        return RandomPolicy()
    return LeRobotPolicy(spec)
