"""``backdrop``: the floor's colour and texture, and the conveyor's frame, legs and rails (the cell's table).

The bins are left alone: each bin is its colour, which is what marks it. The cell has no walls; the sky is left.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from colorsort.shifts.base import Episode, Shift
from colorsort.shifts.registry import register_shift
from colorsort.shifts.surfaces import drawn_colour, dress

FLOOR_AS_BUILT = (0.525, 0.525, 0.525)  # the mean of the floor's checker
FRAME_AS_BUILT = (0.62, 0.64, 0.68)  # frame_mat


@register_shift
class Backdrop(Shift):
    name = "backdrop"
    group = "appearance"
    summary = "the floor (colour and texture) and the conveyor's frame, legs and rails recoloured; bins unchanged"
    unit = "delta E {} from the colours as built, floor {}"
    magnitudes = ((15.0, "plain"), (30.0, "checker"), (45.0, "speckle"))

    def draw(self, level: float, rng: np.random.Generator) -> dict[str, Any]:
        distance, texture = self.magnitude(level)
        return {"floor": {**drawn_colour(FLOOR_AS_BUILT, distance, rng), "texture": texture},
                "frame": drawn_colour(FRAME_AS_BUILT, distance, rng)}

    def apply(self, episode: Episode, level: float, drawn: dict[str, Any], rng: np.random.Generator) -> None:
        m = episode.model
        floor = drawn["floor"]
        dress(m, m.geom("floor").id, "floor", floor["texture"], floor["rgb"])
        m.mat_rgba[m.material("frame_mat").id] = (*drawn["frame"]["rgb"], 1.0)
