"""``box-offset``: boxes set down farther off the belt's centre line than the ``jitter`` variant's 5 cm, to
either side (drawn per box), turned as far as still fits between the rails.

A cube looks the same every 90 degrees, so ``jitter``'s turns of up to 45 degrees already span every turn a
cube can have: this shift holds out the offset, and turns each box within what the belt leaves room for.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from colorsort.shifts.base import Episode, Shift
from colorsort.shifts.registry import register_shift

CLEARANCE = 0.003  # [m] kept between a box's corner and the rail's inner face


def max_yaw(offset: float, half_room: float, half_edge: float) -> float:
    """[rad] the largest turn in [0, pi/4] at which a cube of half edge ``half_edge`` [m], ``offset`` [m] off the
    centre line, stays within ``half_room`` [m] of it: its half-width across the belt, h (|cos| + |sin|)."""
    room = (half_room - offset) / half_edge  # cos + sin may reach this
    if room >= np.sqrt(2):
        return float(np.pi / 4)
    if room <= 1.0:
        return 0.0
    return float(np.pi / 4 - np.arccos(room / np.sqrt(2)))


@register_shift
class BoxOffset(Shift):
    name = "box-offset"
    group = "layout"
    summary = "each box this far off the centre line (side drawn per box; jitter: up to 5 cm), turned as room allows"
    unit = "{} cm off the centre line"
    magnitudes = (5.5, 6.25, 7.0)

    def apply(self, episode: Episode, level: float, drawn: dict[str, Any], rng: np.random.Generator) -> None:
        layout = episode.env.layout
        offset = self.magnitude(level) / 100
        half_room = layout.belt_width / 2 + 0.002 - CLEARANCE  # the rails' inner faces stand 2 mm off the belt
        turn = max_yaw(offset, half_room, layout.box_size / 2)

        def move(spawn):
            side = float(rng.choice([-1.0, 1.0]))
            return dataclasses.replace(spawn, offset=side * offset, yaw=float(rng.uniform(-turn, turn)))

        episode.on_spawn(move)
