"""``box-shade``: each class colour shaded within its class (red toward orange or crimson, green toward teal or
lime, blue toward slate or navy); the label stays. Levels in CIELAB delta E (CIE76) from the class colour."""

from __future__ import annotations

from typing import Any

import numpy as np

from colorsort.config import BIN_COLORS, COLORS
from colorsort.shifts.base import Episode, Shift
from colorsort.shifts.colour import toward
from colorsort.shifts.registry import register_shift

# Per class, the two colours it is shaded toward (one drawn per episode): neighbours within the class's name.
TOWARD: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    "red": ((0.95, 0.45, 0.10), (0.50, 0.02, 0.12)),  # orange, crimson
    "green": ((0.05, 0.55, 0.50), (0.55, 0.90, 0.05)),  # teal, lime
    "blue": ((0.35, 0.45, 0.60), (0.05, 0.08, 0.45)),  # slate, navy
}


def shade(color: str, distance: float, which: int) -> tuple[float, float, float, float]:
    """Class ``color`` shaded ``distance`` [delta E] toward its ``which``-th (0 or 1) neighbour, as rgba."""
    r, g, b = (float(c) for c in toward(COLORS[color][:3], TOWARD[color][which], distance))
    return (r, g, b, 1.0)


@register_shift
class BoxShade(Shift):
    name = "box-shade"
    group = "appearance"
    summary = "each class colour moved in hue, saturation and value within its class (label unchanged)"
    unit = "delta E {} (CIELAB, CIE76)"
    magnitudes = (8.0, 16.0, 24.0)

    def draw(self, level: float, rng: np.random.Generator) -> dict[str, Any]:
        return {"toward": {c: int(rng.integers(2)) for c in BIN_COLORS}}

    def apply(self, episode: Episode, level: float, drawn: dict[str, Any], rng: np.random.Generator) -> None:
        palette = episode.env.plant.pool.palette
        for color, which in drawn["toward"].items():
            palette[color] = shade(color, self.magnitude(level), which)
