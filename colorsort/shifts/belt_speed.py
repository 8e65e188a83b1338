"""``belt-speed``: belt speeds no variant has, slower or faster (drawn per episode)."""

from __future__ import annotations

from typing import Any

import numpy as np

from colorsort.shifts.base import Episode, Shift
from colorsort.shifts.registry import register_shift


@register_shift
class BeltSpeed(Shift):
    name = "belt-speed"
    group = "dynamics"
    summary = "the belt runs slower or faster (drawn per episode) than any variant's 0.05, 0.2 or 0.3 m/s"
    unit = "{} or {} m/s"
    magnitudes = ((0.15, 0.35), (0.12, 0.40), (0.08, 0.45))
    as_built = (0.20, 0.30)  # the stopping belt's speeds: default and fast (training: 0.15-0.2 or 0.3-0.35 m/s)

    def draw(self, level: float, rng: np.random.Generator) -> dict[str, Any]:
        return {"speed_m_s": float(self.magnitude(level)[int(rng.integers(2))])}

    def apply(self, episode: Episode, level: float, drawn: dict[str, Any], rng: np.random.Generator) -> None:
        episode.env.plant.belt.speed = drawn["speed_m_s"]
