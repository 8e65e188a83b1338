"""Argument types the commands share."""

from __future__ import annotations

from colorsort.errors import ConfigError


def parse_image_size(text: str) -> tuple[int, int]:
    """"128" -> (128, 128); "96x128" -> (96, 128) (height x width)."""
    parts = text.lower().split("x")
    try:
        size = tuple(int(p) for p in parts)
    except ValueError:
        raise ConfigError(f"image size {text!r}: give one number (square) or HxW, e.g. 128 or 96x128") from None
    if len(size) == 1:
        return size[0], size[0]
    if len(size) == 2:
        return size[0], size[1]
    raise ConfigError(f"image size {text!r}: give one number (square) or HxW, e.g. 128 or 96x128")

