"""``novel-distractors``: objects no variant has (white, black or cyan; cubes or pucks) among the boxes, to be
let through. They replace boxes the spawner drew, so the rest of the box stream is the control's."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from colorsort.config import NOVEL_COLORS, BoxStyle
from colorsort.shifts.base import Episode, Shift
from colorsort.shifts.registry import register_shift

SHAPES: dict[str, BoxStyle | None] = {"cube": None, "puck": BoxStyle("cylinder", 0.10, 0.07)}


@register_shift
class NovelDistractors(Shift):
    name = "novel-distractors"
    group = "objects"
    summary = f"a share of the boxes replaced by objects of no class ({', '.join(NOVEL_COLORS)}; cube or puck)"
    unit = "{} of the boxes"
    magnitudes = (0.25, 0.33, 0.5)
    trainable = False  # wholly unseen by every recipe

    def apply(self, episode: Episode, level: float, drawn: dict[str, Any], rng: np.random.Generator) -> None:
        share = self.magnitude(level)
        colors, shapes = list(NOVEL_COLORS), list(SHAPES)

        def replace(spawn):
            if rng.uniform() >= share:
                return spawn
            color, shape = colors[int(rng.integers(len(colors)))], shapes[int(rng.integers(len(shapes)))]
            return dataclasses.replace(spawn, color=color, style=SHAPES[shape])

        episode.on_spawn(replace)
