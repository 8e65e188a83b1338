"""``box-shape``: every box becomes an upright cylinder, flatter with the level (a puck), in the class colours."""

from __future__ import annotations

from typing import Any

import numpy as np

from colorsort.config import BoxStyle
from colorsort.shifts.base import Episode, Shift
from colorsort.shifts.registry import register_shift


@register_shift
class BoxShape(Shift):
    name = "box-shape"
    group = "objects"
    summary = "every box an upright cylinder with a flat top: a can at level 1, pucks at 2 and 3 (the ray sees 4 cm up)"
    unit = "cylinder {} cm across, {} cm tall"
    magnitudes = ((10.0, 10.0), (11.0, 7.0), (12.0, 6.0))
    trainable = False  # wholly unseen by every recipe

    def apply(self, episode: Episode, level: float, drawn: dict[str, Any], rng: np.random.Generator) -> None:
        diameter, height = self.magnitude(level)
        episode.env.plant.pool.style = BoxStyle("cylinder", diameter / 100, height / 100)
