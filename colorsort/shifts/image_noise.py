"""``image-noise``: Gaussian pixel noise on every camera image, at each camera's own resolution."""

from __future__ import annotations

from typing import Any

import numpy as np

from colorsort.shifts.base import Episode, Shift
from colorsort.shifts.registry import register_shift


@register_shift
class ImageNoise(Shift):
    name = "image-noise"
    group = "appearance"
    summary = "independent Gaussian noise on every pixel and channel of every camera, the expert's photo included"
    unit = "sigma {} grey levels (of 255)"
    magnitudes = (10.0, 25.0, 50.0)

    def apply(self, episode: Episode, level: float, drawn: dict[str, Any], rng: np.random.Generator) -> None:
        sigma = self.magnitude(level)
        streams: dict[tuple[str, tuple[int, ...]], np.random.Generator] = {}

        def noise(camera: str, image: np.ndarray) -> np.ndarray:
            # one stream per camera and size: filming another camera draws nothing from the policy's
            key = (camera, image.shape)
            if key not in streams:
                streams[key] = episode.generator(self.name, camera, "x".join(map(str, image.shape)))
            noisy = image.astype(np.float32) + streams[key].normal(0.0, sigma, image.shape).astype(np.float32)
            return np.clip(np.round(noisy), 0, 255).astype(np.uint8)

        episode.on_image(noise)
