"""``light-color``: the lamps tinted green or magenta (off the warm-to-cold line the ``lighting`` variant draws
from) and turned, every light the same way."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from colorsort.shifts.base import Episode, Shift, rounded
from colorsort.shifts.registry import register_shift


def tint(strength: float, hue: str) -> np.ndarray:
    """RGB of a lamp: green (1 - s, 1, 1 - s) or magenta (1, 1 - s, 1)."""
    s = strength
    return np.array([1 - s, 1.0, 1 - s]) if hue == "green" else np.array([1.0, 1 - s, 1.0])


@register_shift
class LightColor(Shift):
    name = "light-color"
    group = "appearance"
    summary = "lights tinted green or magenta (1 - weakest channel) and turned about a horizontal axis (azimuth drawn)"
    unit = "tint strength {}, turned {} deg"
    magnitudes = ((0.15, 15.0), (0.30, 30.0), (0.45, 45.0))

    def draw(self, level: float, rng: np.random.Generator) -> dict[str, Any]:
        hue = str(rng.choice(["green", "magenta"]))
        return {"hue": hue, "tint": rounded(tint(self.magnitude(level)[0], hue), 3),
                "tilt_azimuth_deg": round(float(rng.uniform(0, 360)), 1)}

    def apply(self, episode: Episode, level: float, drawn: dict[str, Any], rng: np.random.Generator) -> None:
        tilt = self.magnitude(level)[1]
        lights = episode.env.plant.lights
        lights.tint = np.asarray(drawn["tint"], float)
        lights.apply(episode.env.plant.lighting)
        azimuth = np.deg2rad(drawn["tilt_azimuth_deg"])
        turn = np.zeros(4)
        mujoco.mju_axisAngle2Quat(turn, np.array([np.cos(azimuth), np.sin(azimuth), 0.0]), np.deg2rad(tilt))
        m = episode.model
        for light in range(m.nlight):
            d = np.zeros(3)
            mujoco.mju_rotVecQuat(d, m.light_dir[light].copy(), turn)
            m.light_dir[light] = d
