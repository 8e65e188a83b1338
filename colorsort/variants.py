"""The benchmark suite: named, versioned task variants, each with fixed evaluation seeds.

A variant fixes everything an evaluation depends on: the robot, the task parameters, how many
boxes make an episode, the step limit, domain randomisation, and the seeds. Domain
randomisation changes lights only (brightness and colour temperature of every light); it never
touches a box's or a bin's colour.

Gymnasium ids: ``colorsort/ColorSort-v0`` is the ``default`` variant; each variant ``name`` is
also ``colorsort/ColorSort-<Name>-v<version>`` (see ``Variant.gym_id``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from colorsort.config import COLORS, Lighting, TaskConfig, check_range, make_config, sorting_time_limit
from colorsort.errors import UnknownName
from colorsort.robots import get_robot

EVAL_SEEDS: tuple[int, ...] = tuple(range(10_000, 10_050))  # 50 seeds no collector default reaches
# for choosing among a training run's checkpoints (``colorsort.training.selection``): never scored, never collected
VALIDATION_SEEDS: tuple[int, ...] = tuple(range(20_000, 20_050))
# for held-out shifts (``colorsort.shifts``) and their control arm: apart from evaluation, validation, DAgger's
# take-overs (40,000 on) and the demos (k x 1,000,000 + i)
SHIFT_SEEDS: tuple[int, ...] = tuple(range(30_000, 30_050))

LIGHT_BRIGHTNESS = (0.5, 1.6)  # the ``lighting`` variant's range of light intensity, x the cell's own


def check_brightness(name: str, brightness: tuple[float, float]) -> None:
    """``ValueError`` naming ``name`` unless ``brightness`` is a range (low <= high) within [0.05, 5] x the
    cell's light, the range ``Lighting.brightness`` allows."""
    low, high = brightness
    check_range(f"{name} low", low, 0.05, high)
    check_range(f"{name} high", high, low, 5.0)


@dataclass(frozen=True)
class Variant:
    """One benchmark task.

    Attributes:
        name: lower-case name, e.g. "default".
        version: bumped whenever anything below changes what an episode is.
        description: one line for tables.
        robot: "IRB140", "Panda" or "UR5e".
        preset: the ``TaskConfig`` preset the task starts from.
        overrides: ``TaskConfig`` fields changed from the preset, as (name, value) pairs.
        boxes: an episode ends when this many boxes have left the belt (success if each went
            where it belongs: its colour's bin, or past the end of the belt if it has no bin).
        random_lights: draw a brightness in [0.5, 1.6] and a colour temperature between warm
            (1, 0.8, 0.6) and cold (0.7, 0.85, 1) for every episode.
        seeds: the evaluation seeds, one episode each.
    """

    name: str
    version: int
    description: str
    robot: str = "IRB140"
    preset: str = "default"
    overrides: tuple[tuple[str, object], ...] = ()
    boxes: int = 3
    random_lights: bool = False
    seeds: tuple[int, ...] = field(default=EVAL_SEEDS)

    def __post_init__(self) -> None:
        get_robot(self.robot)  # validates the robot
        _ = self.task_config  # validates the preset and overrides

    @property
    def task_config(self) -> TaskConfig:
        return make_config(self.preset, **dict(self.overrides))

    @property
    def gym_id(self) -> str:
        parts = "".join(p.capitalize() for p in self.name.split("-"))
        return f"colorsort/ColorSort-{parts}-v{self.version}"

    @property
    def time_limit(self) -> float:
        """[s] sim time after which an episode is truncated: a slow but working policy never gets there."""
        return sorting_time_limit(self.boxes, self.task_config)

    def lighting(self, rng: np.random.Generator, brightness: tuple[float, float] | None = None) -> Lighting:
        """This episode's lights, drawn from ``rng`` (plain lights unless ``random_lights``).

        ``brightness`` [x the cell's light] replaces ``LIGHT_BRIGHTNESS`` as the range drawn from (demos
        collected under dimmer or brighter lights than the variant's): the same draws, so episode i's box
        stream and light colour stay those of the variant's episode i."""
        if not self.random_lights:
            return Lighting()
        warm, cold = np.array([1.0, 0.8, 0.6]), np.array([0.7, 0.85, 1.0])
        mix = rng.uniform()
        r, g, b = ((1 - mix) * warm + mix * cold).tolist()
        return Lighting(brightness=float(rng.uniform(*(brightness or LIGHT_BRIGHTNESS))), tint=(r, g, b))


VARIANTS: dict[str, Variant] = {v.name: v for v in (
    Variant("seed", 0, "the original cell: 0.05 m/s belt, a box every 30 s, bins emptied at 2",
            preset="seed", boxes=2),
    Variant("default", 0, "0.2 m/s belt, a box every 4 s"),
    Variant("fast", 0, "0.3 m/s belt, a box every 2.5 s", overrides=(("belt_speed", 0.3), ("spawn_period", 2.5))),
    Variant("jitter", 0, "boxes up to 5 cm off the belt's centre line and turned up to 45 deg",
            overrides=(("lateral_jitter", 0.05), ("yaw_jitter", 45.0))),
    Variant("lighting", 0, "every episode under other lights: brightness x0.5-1.6, warm to cold", random_lights=True),
    Variant("distractors", 0, "yellow and purple boxes too: no bin, must be let through", boxes=4,
            overrides=(("box_colors", tuple(COLORS)),)),
    Variant("tracking", 0, "a belt that never stops: 0.2 m/s, a box every 2.5 s, picked on the move",
            preset="tracking", boxes=5),
    Variant("tracking-fast", 0, "a belt that never stops: 0.3 m/s, a box every 2 s", preset="tracking-fast", boxes=5),
    Variant("tracking-jitter", 0, "the tracking belt with boxes off-centre by up to 5 cm and turned up to 45 deg",
            preset="tracking", boxes=5, overrides=(("lateral_jitter", 0.05), ("yaw_jitter", 45.0))),
    Variant("robots-panda", 0, "the default task with a Franka Panda and the suction cup", robot="Panda"),
    Variant("robots-ur5e", 0, "the default task with a UR5e and the suction cup", robot="UR5e"),
)}
DEFAULT_GYM_ID = "colorsort/ColorSort-v0"


def get_variant(name: str) -> Variant:
    """The variant called ``name``; ValueError naming the valid ones otherwise."""
    if name not in VARIANTS:
        raise UnknownName("variant", name, list(VARIANTS), "variants")
    return VARIANTS[name]


def gym_ids() -> dict[str, str]:
    """Every Gymnasium id -> its variant's name: ``colorsort/ColorSort-v0`` (default) and one per variant."""
    return {DEFAULT_GYM_ID: "default", **{v.gym_id: name for name, v in VARIANTS.items()}}
