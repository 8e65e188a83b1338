"""Recolouring and retexturing a geom for the appearance shifts ``belt-look`` and ``backdrop``.

The arena carries spare materials for them (``shift_<part>_plain``, ``_checker``, ``_speckle``); a shift points
a geom at one and sets the material's colour. Colours are drawn a CIELAB distance [delta E] away from the part's
colour as built, in a direction drawn per episode.
"""

from __future__ import annotations

import numpy as np

from colorsort.shifts.base import rounded
from colorsort.shifts.colour import delta_e, lab_to_srgb, srgb_to_lab


def drawn_colour(base: tuple[float, ...], distance: float, rng: np.random.Generator,
                 max_chroma: float = 25.0) -> dict:
    """A colour about ``distance`` [delta E] from ``base``: a hue angle and a lightness sign drawn, chroma kept
    under ``max_chroma`` (these are floors, belts and frames, not coloured parts). Records the delta E reached."""
    lab = srgb_to_lab(base)
    angle, sign = float(rng.uniform(0, 2 * np.pi)), float(rng.choice([-1.0, 1.0]))
    chroma = min(max_chroma, 0.6 * distance)
    dl = sign * np.sqrt(max(distance**2 - chroma**2, 0.0))
    if not 2.0 < lab[0] + dl < 98.0:
        dl = -dl  # no room that way: the other way
    target = lab + np.array([dl, chroma * np.cos(angle), chroma * np.sin(angle)])
    rgb = lab_to_srgb(target)
    return {"rgb": rounded(rgb), "delta_e": round(delta_e(base, rgb), 1)}


def dress(model, geom: int, part: str, texture: str, rgb: list[float]) -> None:
    """Point ``geom`` at the spare material ``shift_<part>_<texture>`` coloured ``rgb``."""
    mat = model.material(f"shift_{part}_{texture}").id
    model.geom_matid[geom] = mat
    model.mat_rgba[mat] = (*rgb, 1.0)
