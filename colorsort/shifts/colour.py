"""Colour arithmetic for the appearance shifts: sRGB <-> CIELAB (D65) and the CIE76 colour difference.

Model colours (MuJoCo rgba) are treated as sRGB, as the renderer writes them to the image.
"""

from __future__ import annotations

import numpy as np

_M = np.array([[0.4124564, 0.3575761, 0.1804375], [0.2126729, 0.7151522, 0.0721750],
               [0.0193339, 0.1191920, 0.9503041]])  # linear sRGB -> XYZ
_WHITE = _M @ np.ones(3)  # D65


def linear(c: np.ndarray) -> np.ndarray:
    """Linear RGB of sRGB values ``c`` (any shape ending in 3; 1 is full scale, values above it kept)."""
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def lab_of_linear(lin: np.ndarray) -> np.ndarray:
    """CIELAB (L* in [0, 100] for colours in gamut) of linear RGB (any shape ending in 3)."""
    t = (lin @ _M.T) / _WHITE
    f = np.where(t > (6 / 29) ** 3, np.cbrt(t), t / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])], axis=-1)


def srgb_to_lab(rgb: np.ndarray | tuple[float, ...]) -> np.ndarray:
    """CIELAB (L* in [0, 100]) of an sRGB colour in [0, 1]^3."""
    return lab_of_linear(linear(np.clip(np.asarray(rgb, float)[:3], 0.0, 1.0)))


def lab_to_srgb(lab: np.ndarray) -> np.ndarray:
    """sRGB in [0, 1]^3 of a CIELAB colour (clipped to the gamut)."""
    L, a, b = lab
    fy = (L + 16) / 116
    f = np.array([fy + a / 500, fy, fy - b / 200])
    t = np.where(f > 6 / 29, f**3, 3 * (6 / 29) ** 2 * (f - 4 / 29)) * _WHITE
    linear = np.clip(np.linalg.solve(_M, t), 0.0, 1.0)
    return np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * linear ** (1 / 2.4) - 0.055)


def delta_e(a: np.ndarray | tuple[float, ...], b: np.ndarray | tuple[float, ...]) -> float:
    """CIE76 colour difference (Euclidean distance in CIELAB) of two sRGB colours."""
    return float(np.linalg.norm(srgb_to_lab(a) - srgb_to_lab(b)))


def toward(rgb: tuple[float, ...], target: tuple[float, ...], distance: float) -> np.ndarray:
    """The sRGB colour ``distance`` [delta E] from ``rgb`` along the CIELAB line toward ``target``, found by
    bisection on the rendered (gamut-clipped) colour, so that its delta E from ``rgb`` is ``distance``."""
    start, end = srgb_to_lab(rgb), srgb_to_lab(target)
    lo, hi = 0.0, 1.0
    for _ in range(50):
        mid = (lo + hi) / 2
        if delta_e(rgb, lab_to_srgb(start + mid * (end - start))) < distance:
            lo = mid
        else:
            hi = mid
    return lab_to_srgb(start + hi * (end - start))
