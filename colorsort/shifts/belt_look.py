"""``belt-look``: the belt's colour and texture."""

from __future__ import annotations

from typing import Any

import numpy as np

from colorsort.shifts.base import Episode, Shift
from colorsort.shifts.registry import register_shift
from colorsort.shifts.surfaces import drawn_colour, dress

BELT_AS_BUILT = (0.12, 0.12, 0.13)  # the arena's belt_mat


@register_shift
class BeltLook(Shift):
    name = "belt-look"
    group = "appearance"
    summary = "the belt recoloured (hue drawn, low chroma) and, at levels 2 and 3, textured (checker, speckle)"
    unit = "delta E {} from the belt as built, {}"
    magnitudes = ((12.0, "plain"), (24.0, "checker"), (36.0, "speckle"))

    def draw(self, level: float, rng: np.random.Generator) -> dict[str, Any]:
        distance, texture = self.magnitude(level)
        return {**drawn_colour(BELT_AS_BUILT, distance, rng), "texture": texture}

    def apply(self, episode: Episode, level: float, drawn: dict[str, Any], rng: np.random.Generator) -> None:
        m = episode.model
        dress(m, m.geom("belt_surface").id, "belt", drawn["texture"], drawn["rgb"])
