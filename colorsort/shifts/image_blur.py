"""``image-blur``: defocus or motion blur (drawn per episode) on every camera image, sized in a fraction of the
image's width so that it is the same blur at every resolution."""

from __future__ import annotations

from typing import Any

import cv2
import numpy as np

from colorsort.shifts.base import Episode, Shift
from colorsort.shifts.registry import register_shift


def motion_kernel(length: int, angle_deg: float) -> np.ndarray:
    """A normalised line kernel ``length`` px long at ``angle_deg``."""
    size = length if length % 2 else length + 1
    kernel = np.zeros((size, size), np.float32)
    c = size // 2
    dx, dy = np.cos(np.deg2rad(angle_deg)), np.sin(np.deg2rad(angle_deg))
    for t in np.linspace(-(length - 1) / 2, (length - 1) / 2, 4 * length):
        kernel[int(round(c + t * dy)), int(round(c + t * dx))] = 1.0
    return kernel / kernel.sum()


@register_shift
class ImageBlur(Shift):
    name = "image-blur"
    group = "appearance"
    summary = "defocus (Gaussian, sigma) or motion blur (a line 4 sigma long, angle drawn) on every camera"
    unit = "sigma {} % of the image width"
    magnitudes = (0.5, 1.0, 2.0)
    trainable = False  # at 32-64 px the motion kernel below level 1 is level 1's (2 px)

    def draw(self, level: float, rng: np.random.Generator) -> dict[str, Any]:
        return {"kind": str(rng.choice(["defocus", "motion"])), "angle_deg": round(float(rng.uniform(0, 180)), 1)}

    def apply(self, episode: Episode, level: float, drawn: dict[str, Any], rng: np.random.Generator) -> None:
        fraction = self.magnitude(level) / 100

        def blur(camera: str, image: np.ndarray) -> np.ndarray:
            sigma = fraction * image.shape[1]  # [px] at this camera's resolution
            if drawn["kind"] == "defocus":
                return cv2.GaussianBlur(image, (0, 0), sigmaX=sigma, sigmaY=sigma, borderType=cv2.BORDER_REFLECT)
            kernel = motion_kernel(max(2, int(round(4 * sigma))), drawn["angle_deg"])
            return cv2.filter2D(image, -1, kernel, borderType=cv2.BORDER_REFLECT)

        episode.on_image(blur)
