"""``joint-noise``: Gaussian noise on every joint target of every action (a drive's command noise)."""

from __future__ import annotations

from typing import Any

import numpy as np

from colorsort.shifts.base import Episode, Shift
from colorsort.shifts.registry import register_shift


@register_shift
class JointNoise(Shift):
    name = "joint-noise"
    group = "dynamics"
    summary = "independent Gaussian noise added to each joint target at every control step"
    unit = "sigma {} rad per joint target"
    magnitudes = (0.005, 0.01, 0.02)

    def apply(self, episode: Episode, level: float, drawn: dict[str, Any], rng: np.random.Generator) -> None:
        sigma, joints = self.magnitude(level), len(episode.env.robots[0].robot_joints)

        def noise(action: np.ndarray) -> np.ndarray:
            out = np.array(action, dtype=float)
            out[:joints] += rng.normal(0.0, sigma, joints)
            return out

        episode.on_action(noise)
