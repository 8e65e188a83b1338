"""An episode's random draws, made on the host from its seed exactly as the CPU cell makes them.

The CPU cell draws from its env's generator (``numpy.random.default_rng(seed)``) in this order:
robosuite's initial joint noise (one normal draw per arm joint, scaled by a magnitude of 0), the
first box at the reset (colour, lateral offset, yaw: ``conveyor.Spawner``), then the variant's lights
(``Variant.lighting``), then each later box as it spawns. A box's draws do not depend on when it
spawns, so the whole stream of boxes is known at the reset: the batched cell takes it as a table.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from colorsort.config import COLORS, Lighting, TaskConfig
from colorsort.robots import get_robot
from colorsort.variants import Variant

COLOR_NAMES = tuple(COLORS)


@dataclass(frozen=True)
class EpisodeDraws:
    """One episode's boxes, in order of appearance, and its lights.

    Attributes:
        color: (boxes,) int, index in ``config.COLORS``.
        offset: (boxes,) [m] from the belt's centre line.
        yaw: (boxes,) [rad] about z.
        lighting: the episode's lights.
    """

    color: np.ndarray
    offset: np.ndarray
    yaw: np.ndarray
    lighting: Lighting


def _box(rng: np.random.Generator, config: TaskConfig) -> tuple[int, float, float]:
    color = str(rng.choice(config.box_colors))
    dy = rng.uniform(-config.lateral_jitter, config.lateral_jitter)
    yaw = np.deg2rad(rng.uniform(-config.yaw_jitter, config.yaw_jitter))
    return COLOR_NAMES.index(color), float(dy), float(yaw)


def episode_draws(variant: Variant, seed: int, boxes: int) -> EpisodeDraws:
    """The first ``boxes`` boxes and the lights of ``variant``'s episode ``seed``."""
    config = variant.task_config
    rng = np.random.default_rng(seed)
    rng.standard_normal(get_robot(variant.robot).n_joints)  # robosuite's initialization noise
    first = _box(rng, config)
    lighting = variant.lighting(rng)
    rows = [first] + [_box(rng, config) for _ in range(boxes - 1)]
    color, offset, yaw = (np.array(col) for col in zip(*rows, strict=True))
    return EpisodeDraws(color.astype(np.int32), offset, yaw, lighting)


def max_spawns(variant: Variant, control_freq: float, steps: int) -> int:
    """An upper bound on the boxes an episode of ``steps`` control steps can spawn (one per spawn period,
    plus the first)."""
    seconds = steps / control_freq
    return int(np.ceil(seconds / variant.task_config.spawn_period)) + 2
