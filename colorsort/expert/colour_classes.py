"""The colour sensor's classes, taught from sample parts: regions in CIELAB, and the lights they were taught under.

A class is the CIELAB colour of its sample part's top face as the sensor photographed it (``teach.py``), and
every colour within ``tolerance`` (CIE76 delta E) of it. Two things are taken out of a pixel before it is
compared, because neither is the part's colour:

- **the light**: each photo is white-balanced against two surfaces of the cell that are always in view, the
  belt's rails and the belt, whose colours were taught with the classes. When both have changed by the same
  per-channel gain, the light changed (brighter, dimmer, tinted), and the image is divided by that gain (von
  Kries). When they disagree, one of the surfaces was repainted, not the light changed, and nothing is
  corrected.
- **the shading**: a pixel is scaled to the class's brightness (its largest value, as the renderer writes
  them: a face in a shadow, turned from the lamps or under a dimmer one has every value scaled alike) before its
  CIELAB colour is taken, so it is compared by its chromaticity at the class's lightness.

The table of distances that sets ``tolerance``: ``benchmarks/bench_colours.py`` (docs/expert.md).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from colorsort.errors import ConfigError
from colorsort.paths import ASSETS_DIR
from colorsort.shifts.colour import lab_of_linear, lab_to_srgb, linear

SHIPPED = ASSETS_DIR / "sensor" / "taught_colours.json"  # what ``python -m colorsort.expert.teach`` writes
AGREEMENT = 0.1  # largest |log| difference between the rails' and the belt's gains that counts as the same light

Triple = tuple[float, float, float]


def triple(values) -> Triple:
    """Three numbers as a tuple of floats (a colour)."""
    a, b, c = (float(v) for v in values)
    return (a, b, c)


@dataclass(frozen=True)
class TaughtColours:
    """What the teach step learnt: each class's colour, and the rails' and belt's under the same lights.

    Attributes:
        centres: class name -> CIELAB (L*, a*, b*) of its sample's top face, as photographed.
        rails: median RGB [0-255] of the rails' top faces in the same photos.
        belt: median RGB [0-255] of the belt in the same photos.
        photo_size: [px] the side of the photos.
    """

    centres: dict[str, Triple]
    rails: Triple
    belt: Triple
    photo_size: int

    def to_json(self) -> dict:
        return {"centres": {k: [round(float(x), 3) for x in v] for k, v in self.centres.items()},
                "rails": [round(float(x), 3) for x in self.rails], "belt": [round(float(x), 3) for x in self.belt],
                "photo_size": self.photo_size}

    @classmethod
    def from_json(cls, data: dict) -> TaughtColours:
        return cls({k: triple(v) for k, v in data["centres"].items()}, triple(data["rails"]), triple(data["belt"]),
                   int(data["photo_size"]))

    @classmethod
    def load(cls, path: Path = SHIPPED) -> TaughtColours:
        """The classes taught once for the cell as built (``python -m colorsort.expert.teach`` wrote them)."""
        return cls.from_json(json.loads(Path(path).read_text()))

    def save(self, path: Path = SHIPPED) -> None:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        Path(path).write_text(json.dumps(self.to_json(), indent=1) + "\n")


class ColourClasses:
    """Labels pixels with taught classes.

    Args:
        taught: the teach step's result.
        names: the classes to report (each taught).
        tolerance: [delta E, CIE76] the largest distance from a class's colour, at its lightness, still in it.
    """

    def __init__(self, taught: TaughtColours, names: tuple[str, ...], tolerance: float):
        missing = [n for n in names if n not in taught.centres]
        if missing:
            raise ConfigError(f"colour classes {missing} were not taught; taught: {sorted(taught.centres)}")
        self.names, self.tolerance = names, tolerance
        self._lab = np.array([taught.centres[n] for n in names])  # (k, 3)
        self._brightness = np.array([255 * lab_to_srgb(lab).max() for lab in self._lab])  # (k,) [0-255]
        self._rails, self._belt = np.asarray(taught.rails, float), np.asarray(taught.belt, float)

    def light_gain(self, rails: np.ndarray, belt: np.ndarray) -> np.ndarray:
        """Per-channel gain (3,) that undoes a change of light, from the median RGB of the ``rails`` and the ``belt``
        now: the rails' gain when the belt's agrees with it (the light changed), else ones (a surface changed)."""
        g_rails = self._rails / np.maximum(rails, 1.0)
        g_belt = self._belt / np.maximum(belt, 1.0)
        if np.max(np.abs(np.log(g_rails) - np.log(g_belt))) > AGREEMENT:
            return np.ones(3)
        return np.clip(g_rails, 0.2, 5.0)

    def distances(self, rgb: np.ndarray) -> np.ndarray:
        """[delta E] of each pixel of ``rgb`` (..., 3) [0-255, light-corrected] from each class, the pixel scaled to
        the class's brightness, (..., k)."""
        rgb = np.asarray(rgb, np.float64)
        brightness = np.maximum(rgb.max(axis=-1), 1.0)[..., None, None]  # (..., 1, 1)
        scaled = rgb[..., None, :] * (self._brightness[:, None] / brightness)  # (..., k, 3)
        return np.linalg.norm(lab_of_linear(linear(scaled / 255.0)) - self._lab, axis=-1)

    def label(self, rgb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(class index per pixel, ``len(names)`` where none is within ``tolerance``; the distance to the nearest
        class [delta E]) of ``rgb`` (..., 3)."""
        d = self.distances(rgb)
        nearest = d.argmin(axis=-1)
        best = np.take_along_axis(d, nearest[..., None], axis=-1)[..., 0]
        return np.where(best <= self.tolerance, nearest, len(self.names)), best
