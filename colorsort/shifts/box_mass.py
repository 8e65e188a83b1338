"""``box-mass``: heavier boxes, and less friction between boxes and belt."""

from __future__ import annotations

from typing import Any

import numpy as np

from colorsort.shifts.base import Episode, Shift
from colorsort.shifts.registry import register_shift


@register_shift
class BoxMass(Shift):
    name = "box-mass"
    group = "objects"
    summary = "every box heavier (inertia scaled with it) and box-belt sliding friction lower (both geoms set)"
    unit = "{} kg, friction {} (cell: 0.5 kg, 1.0)"
    magnitudes = ((1.0, 0.8), (1.5, 0.6), (2.5, 0.4))
    as_built = (0.5, 1.0)  # TaskConfig.box_mass, the arena's box and belt friction

    def apply(self, episode: Episode, level: float, drawn: dict[str, Any], rng: np.random.Generator) -> None:
        mass, friction = self.magnitude(level)
        m, pool = episode.model, episode.env.plant.pool
        for body, geom in zip(pool.body, pool.geom, strict=True):
            m.body_inertia[body] *= mass / m.body_mass[body]
            m.body_mass[body] = mass
            m.geom_friction[geom, 0] = friction
        m.geom_friction[m.geom("belt_surface").id, 0] = friction  # MuJoCo takes the larger of the two
