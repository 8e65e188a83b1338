"""``box-size``: every box of the episode smaller or larger (drawn per episode) than the cell's 10 cm cube.

Its mass stays the cell's (``box-mass`` changes that); its inertia follows its size.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from colorsort.config import BoxStyle
from colorsort.shifts.base import Episode, Shift
from colorsort.shifts.registry import register_shift


@register_shift
class BoxSize(Shift):
    name = "box-size"
    group = "objects"
    summary = "every box's edge changed by the level, smaller or larger (drawn per episode)"
    unit = "edge 10 cm -/+ {} cm"
    magnitudes = (1.0, 2.0, 3.0)

    def draw(self, level: float, rng: np.random.Generator) -> dict[str, Any]:
        edge = 10.0 + float(rng.choice([-1.0, 1.0])) * self.magnitude(level)
        return {"edge_cm": edge}

    def apply(self, episode: Episode, level: float, drawn: dict[str, Any], rng: np.random.Generator) -> None:
        pool = episode.env.plant.pool
        scale = drawn["edge_cm"] / 100 / pool.layout.box_size
        base = pool.style or BoxStyle("box", pool.layout.box_size, pool.layout.box_size)
        pool.style = BoxStyle(base.shape, base.width * scale, base.height * scale)
