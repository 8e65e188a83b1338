"""Task configuration: the cell's fixed layout, the tunable task parameters with presets, and lights.

Everything is a frozen dataclass; ``make_config("seed", belt_speed=0.08)`` picks a preset and
overrides fields one by one, validating every value. Per-robot data lives in ``robots.py``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from colorsort.errors import ConfigError, UnknownName

# Box and bin colours the cell knows, as RGBA in [0, 1]. Red, green and blue have bins.
COLORS: dict[str, tuple[float, float, float, float]] = {
    "red": (0.85, 0.10, 0.10, 1.0),
    "green": (0.10, 0.70, 0.15, 1.0),
    "blue": (0.10, 0.25, 0.85, 1.0),
    "yellow": (0.90, 0.80, 0.10, 1.0),
    "purple": (0.55, 0.15, 0.65, 1.0),
}
BIN_COLORS: tuple[str, ...] = ("red", "green", "blue")
# The cell's two implementations: "cpu", a robosuite env per world; "warp", MuJoCo Warp's batched cell
# (colorsort.batched, imported only when chosen: the default install has no Warp).
BACKENDS: tuple[str, ...] = ("cpu", "warp")
BOX, CYLINDER = 6, 5  # MuJoCo's mjGEOM_BOX and mjGEOM_CYLINDER (tests/test_shifts.py holds them to mujoco's)
# Colours no variant and no recipe has: the ``novel-distractors`` shift's objects (``colorsort.shifts``). A task
# config cannot name them, and they have no place in the ``next_box`` one-hot, so no policy ever trains on them.
NOVEL_COLORS: dict[str, tuple[float, float, float, float]] = {
    "white": (0.92, 0.92, 0.90, 1.0),
    "black": (0.08, 0.08, 0.09, 1.0),
    "cyan": (0.10, 0.75, 0.80, 1.0),
}
ALL_COLORS: dict[str, tuple[float, float, float, float]] = {**COLORS, **NOVEL_COLORS}  # sim-state colour indices
@dataclass(frozen=True)
class CellLayout:
    """Where things stand, in the world frame [m]; the robot base is at the origin on the floor.

    The original CoppeliaSim cell put the blue bin 0.88 m from the arm, beyond the IRB 140's
    0.81 m reach; this layout keeps its topology (belt on the arm's right running toward it,
    bins in front in a row 0.325 m apart along y) and moves everything within reach.
    """

    belt_start_x: float = 1.30  # upstream end, where boxes appear
    belt_end_x: float = 0.20  # downstream end: boxes riding past it fall off
    belt_y: float = -0.40  # belt centre line
    belt_width: float = 0.25
    belt_top_z: float = 0.40  # height of the belt's carrying surface
    sensor_x: float = 0.35  # the ray across the belt; a box stops with its leading face here
    sensor_height: float = 0.04  # ray height above the belt surface: under the top of the lowest box the cell accepts
    spawn_x: float = 1.22  # box centre at spawn
    box_size: float = 0.10  # cube edge
    tallest_box: float = 0.15  # [m] the tallest box the cell accepts: the expert's touch-off starts over it
    bin_x: float = 0.42  # bin centres
    bin_y0: float = -0.05  # red bin centre; green and blue follow at +bin_spacing
    bin_spacing: float = 0.325
    bin_size: tuple[float, float, float] = (0.46, 0.31, 0.30)  # outer x, y, height
    bin_wall: float = 0.01

    @property
    def sensor_range(self) -> float:
        """Length of the ray [m]: it spans the belt and ends before the far rail."""
        return self.belt_width + 0.02

    @property
    def pick_point(self) -> tuple[float, float, float]:
        """Centre of a box's top face when it stops at the sensor."""
        half = self.box_size / 2
        return (self.sensor_x + half, self.belt_y, self.belt_top_z + self.box_size)

    @property
    def shortest_box(self) -> float:
        """[m] the lowest box the cell accepts: the ray's height (a lower one rides under it unseen)."""
        return self.sensor_height

    def bin_center(self, index: int) -> tuple[float, float]:
        """(x, y) of bin ``index`` (0 = red, 1 = green, 2 = blue)."""
        return (self.bin_x, self.bin_y0 + index * self.bin_spacing)


@dataclass(frozen=True)
class BoxStyle:
    """A box's shape, when it is not the cell's cube: a ``"box"`` of ``width`` x ``width`` x ``height`` [m] or an
    upright ``"cylinder"`` (a puck) of diameter ``width`` and ``height`` [m]; both have a flat top."""

    shape: str
    width: float
    height: float

    def geometry(self) -> tuple[int, tuple[float, float, float], float, tuple[float, float, float]]:
        """MuJoCo's geom type, size, bounding radius and axis-aligned half-extents of this style."""
        w, h = self.width / 2, self.height / 2
        if self.shape == "cylinder":
            return CYLINDER, (w, h, 0.0), float(np.hypot(w, h)), (w, w, h)
        return BOX, (w, w, h), float(np.sqrt(2 * w * w + h * h)), (w, w, h)

    def inertia(self, mass: float) -> tuple[float, float, float]:
        """Principal moments [kg m^2] of a solid body of this style and ``mass`` [kg]."""
        w, h = self.width, self.height
        if self.shape == "cylinder":
            r2 = (w / 2) ** 2
            side = mass * (3 * r2 + h * h) / 12
            return side, side, mass * r2 / 2
        return mass * (w * w + h * h) / 12, mass * (w * w + h * h) / 12, mass * w * w / 6


@dataclass(frozen=True)
class TaskConfig:
    """The task's tunable parameters. Units in brackets."""

    belt_speed: float = 0.20  # [m/s] belt surface speed while running
    spawn_period: float = 4.0  # [s] sim time between box appearances
    bin_capacity: int = 4  # boxes a bin holds before it is emptied
    boxes_to_sort: int = 5  # correctly placed boxes that make an episode a success
    box_colors: tuple[str, ...] = BIN_COLORS  # colours drawn (uniformly) for new boxes
    pool_size: int = 16  # boxes allocated when the model is built (in bins, on the belt, in the cup)
    lateral_jitter: float = 0.0  # [m] max |offset| of a new box from the belt centre line
    yaw_jitter: float = 0.0  # [deg] max |yaw| of a new box
    box_mass: float = 0.5  # [kg]
    time_limit: float = 60.0  # [s] sim time per episode (sets robosuite's horizon)
    tracking: bool = False  # the belt never stops: the ray only reports that a box passed (conveyor tracking)

    def __post_init__(self) -> None:
        check_range("belt_speed", self.belt_speed, 0.0, 0.5, low_inclusive=False)
        check_range("spawn_period", self.spawn_period, 0.5, 600.0)
        check_range("bin_capacity", self.bin_capacity, 1, 100)
        check_range("boxes_to_sort", self.boxes_to_sort, 1, 10_000)
        check_range("pool_size", self.pool_size, 1, 64)
        check_range("lateral_jitter", self.lateral_jitter, 0.0, 0.06)
        check_range("yaw_jitter", self.yaw_jitter, 0.0, 45.0)
        check_range("box_mass", self.box_mass, 0.05, 5.0)
        check_range("time_limit", self.time_limit, 1.0, 36_000.0)
        # Bins hold up to bin_capacity - 1 boxes each between emptyings; with fewer boxes than
        # that plus two, the pool could end up entirely in bins and the spawner would starve.
        min_pool = len(BIN_COLORS) * (self.bin_capacity - 1) + 2
        if self.pool_size < min_pool:
            raise ConfigError(
                f"pool_size={self.pool_size} is too small for bin_capacity={self.bin_capacity}: "
                f"valid values lie in [{min_pool}, 64] (3 bins x (capacity - 1) + 2)"
            )
        if isinstance(self.box_colors, str) or not self.box_colors:
            raise ConfigError(f"box_colors must be a non-empty tuple of colours from {sorted(COLORS)}")
        unknown = [c for c in self.box_colors if c not in COLORS]
        if unknown:
            raise UnknownName("box colour(s)", unknown, sorted(COLORS), "colours")
        object.__setattr__(self, "box_colors", tuple(self.box_colors))


def check_range(name: str, value: float, low: float, high: float, low_inclusive: bool = True) -> None:
    """``ValueError`` naming ``name`` and the valid interval unless ``low <= value <= high``
    (``low < value`` when not ``low_inclusive``)."""
    ok_low = value >= low if low_inclusive else value > low
    if not (ok_low and value <= high):
        bracket = "[" if low_inclusive else "("
        raise ConfigError(f"{name}={value!r} is out of range; valid values lie in {bracket}{low}, {high}]")


PRESETS: dict[str, TaskConfig] = {
    # The original tutorial's numbers: a box every 30 s at 0.05 m/s, bins emptied at 2 boxes.
    "seed": TaskConfig(belt_speed=0.05, spawn_period=30.0, bin_capacity=2, boxes_to_sort=3, time_limit=150.0),
    # Four times the original's belt speed, a box every 4 s: room for 15 boxes a minute.
    "default": TaskConfig(),
    # Conveyor tracking: the belt never stops; the arm meets each box on the move. 24 boxes a minute.
    "tracking": TaskConfig(spawn_period=2.5, tracking=True),
    "tracking-fast": TaskConfig(belt_speed=0.3, spawn_period=2.0, tracking=True),  # 30 boxes a minute
}

TRACKING_SENSOR_X = 0.80  # [m] where the ray and the colour camera stand on a tracking belt


def layout_for(task: TaskConfig) -> CellLayout:
    """The cell a task runs in. On a tracking belt the ray and the colour camera stand upstream, at
    ``TRACKING_SENSOR_X``, beyond the arm's reach: the camera sees each box before the arm can meet it."""
    return CellLayout(sensor_x=TRACKING_SENSOR_X) if task.tracking else CellLayout()


def is_distractor(color: str) -> bool:
    """A box colour with no bin: the right thing is to let it through."""
    return color not in BIN_COLORS


@dataclass(frozen=True)
class Lighting:
    """One lighting and sensor condition (``cell.lighting`` applies it; it never recolours boxes or bins).

    Attributes:
        brightness: scale of every light's intensity (1 = as built; 0.5 = half, 2 = double).
        tint: RGB colour of the light, each in (0, 1]; (1, 1, 1) is white.
        noise_std: standard deviation of Gaussian sensor noise [8-bit intensity levels].
        shadow: fraction of light removed inside a shadow band across the image, in [0, 1).
    """

    brightness: float = 1.0
    tint: tuple[float, float, float] = (1.0, 1.0, 1.0)
    noise_std: float = 0.0
    shadow: float = 0.0

    def __post_init__(self) -> None:
        check_range("brightness", self.brightness, 0.05, 5.0)
        if len(self.tint) != 3 or not all(0.0 < t <= 1.0 for t in self.tint):
            raise ConfigError(f"tint={self.tint} must be three values in (0, 1]")
        check_range("noise_std", self.noise_std, 0.0, 50.0)
        if not 0.0 <= self.shadow < 1.0:
            raise ConfigError(f"shadow={self.shadow!r} is out of range; valid values lie in [0.0, 1.0)")


def sorting_time_limit(boxes: int, task: TaskConfig) -> float:
    """[s] sim time a working policy never needs for ``boxes`` boxes to leave the belt: three
    spawn periods per box, plus a minute, plus the ride down the belt."""
    return 3.0 * boxes * task.spawn_period + 60.0 + 1.5 / task.belt_speed


def make_config(preset: str = "default", **overrides: Any) -> TaskConfig:
    """A preset's ``TaskConfig`` with fields overridden by keyword.

    Raises:
        ValueError: unknown preset, unknown field, or an invalid value.
    """
    if preset not in PRESETS:
        raise UnknownName("preset", preset, sorted(PRESETS), "presets")
    fields = {f.name for f in dataclasses.fields(TaskConfig)}
    unknown = sorted(set(overrides) - fields)
    if unknown:
        raise UnknownName("config field(s)", unknown, sorted(fields), "fields")
    return dataclasses.replace(PRESETS[preset], **overrides)
