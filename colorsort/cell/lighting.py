"""Lighting and sensor conditions a real cell sees: brightness, light colour, noise and shadows.

A ``Lighting`` (``config.py``) describes one condition. ``LightRig`` changes the intensity and
colour of a MuJoCo model's lights (scene lights and the headlight) from the values it was built
with; ``sensor_effects`` adds what happens in the camera and on the surfaces after rendering
(sensor noise, a shadow band). Neither touches the colours of boxes or bins.
"""

from __future__ import annotations

import mujoco
import numpy as np

from colorsort.config import Lighting

# The conditions the colour sensor is benchmarked under (benchmarks/bench_perception.py).
CONDITIONS: dict[str, Lighting] = {
    "normal": Lighting(),
    "dim": Lighting(brightness=0.5),
    "bright": Lighting(brightness=2.0),
    "warm": Lighting(tint=(1.0, 0.80, 0.60)),  # about 3,000 K
    "cold": Lighting(tint=(0.70, 0.85, 1.0)),  # about 9,000 K
    "noise": Lighting(noise_std=10.0),
    "shadow": Lighting(shadow=0.6),
}


class LightRig:
    """Sets a model's lights to a ``Lighting``, relative to the values captured at construction."""

    def __init__(self, model: mujoco.MjModel):
        self.model = model
        self.tint: np.ndarray = np.ones(3)  # the lamps' own colour under every ``Lighting`` (light-color shift)
        self._diffuse = model.light_diffuse.copy()
        self._ambient = model.light_ambient.copy()
        self._specular = model.light_specular.copy()
        h = model.vis.headlight
        self._head = (h.ambient.copy(), h.diffuse.copy(), h.specular.copy())

    def apply(self, lighting: Lighting, model: mujoco.MjModel | None = None) -> None:
        """Set the lights to ``lighting``: those of this rig's model, or of ``model`` (a copy of it)."""
        scale = lighting.brightness * np.asarray(lighting.tint) * self.tint
        m = self.model if model is None else model
        m.light_diffuse[:] = self._diffuse * scale
        m.light_ambient[:] = self._ambient * scale
        m.light_specular[:] = self._specular * scale
        h = m.vis.headlight
        h.ambient[:], h.diffuse[:], h.specular[:] = (v * scale for v in self._head)

    def restore(self) -> None:
        self.apply(Lighting())


def sensor_effects(image: np.ndarray, lighting: Lighting, rng: np.random.Generator) -> np.ndarray:
    """``image`` (H, W, 3) uint8 with a random shadow band and sensor noise as ``lighting`` asks.

    The shadow is a straight-edged band of random direction and width (a rail, a cable or an arm
    between the light and the belt), darkening what lies in it by ``lighting.shadow``.
    """
    if lighting.shadow == 0.0 and lighting.noise_std == 0.0:
        return image
    out = image.astype(np.float32)
    h, w = image.shape[:2]
    if lighting.shadow > 0.0:
        angle = rng.uniform(0, np.pi)
        normal = np.array([np.cos(angle), np.sin(angle)])
        rows, cols = np.mgrid[0:h, 0:w]
        s = (cols - w / 2) * normal[0] + (rows - h / 2) * normal[1]  # signed distance [px]
        centre, width = rng.uniform(-0.3, 0.3) * h, rng.uniform(0.15, 0.5) * h
        inside = np.clip(width / 2 - np.abs(s - centre) + 0.5, 0.0, 1.0)  # 1 px soft edge
        out *= (1.0 - lighting.shadow * inside)[..., None]
    if lighting.noise_std > 0.0:
        out += rng.normal(0.0, lighting.noise_std, out.shape)
    return np.clip(np.round(out), 0, 255).astype(np.uint8)

__all__ = ["CONDITIONS", "LightRig", "Lighting", "sensor_effects"]
