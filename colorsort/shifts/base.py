"""What a held-out shift is: a factor of the cell with levels 0 to 3 in physical units.

A ``Shift`` draws its values for an episode (``draw``: a direction, a sign, a choice) from the episode's own
generator and applies them to the cell (``apply``) at reset, through an ``EpisodeShift`` (``episode.py``): the
model (cameras, lights, materials, masses), the pool's palette and box style, the belt's speed, the arm's start,
and three hooks for what happens later in the episode (each new box, each rendered image, each action).
Level 0 is no change; a shift never runs at level 0. Levels 1-3 are held out: for evaluation only, no recipe
trains on them (``docs/shifts.md``). A ``trainable`` shift also has a training range, the values strictly between
the cell as built and level 1: ``NAME:train`` draws a fraction of the way there per episode, which is what a
randomised recipe (``-dr``) records its demos with.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

import mujoco
import numpy as np

from colorsort.config import CellLayout, TaskConfig

if TYPE_CHECKING:
    from colorsort.cell.conveyor import Spawn
    from colorsort.cell.plant import Plant

LEVELS: tuple[int, ...] = (0, 1, 2, 3)
TRAIN = "train"  # ``NAME:train``: per episode, a value drawn strictly between the cell as built and level 1
GROUPS: tuple[str, ...] = ("viewpoint", "appearance", "objects", "dynamics", "layout")


class Cell(Protocol):
    """What shifts reach of a ``Cell`` env (``envs/robosuite_task.py``): its model and data, plant, arm and settings."""

    config: TaskConfig
    layout: CellLayout
    plant: Plant
    robots: list[Any]
    rng: np.random.Generator

    @property
    def mj_model(self) -> mujoco.MjModel: ...

    @property
    def mj_data(self) -> mujoco.MjData: ...

    @property
    def sim(self) -> Any: ...

class Episode(Protocol):
    """What a shift applies itself through: the env, its model, generators and hooks (``episode.EpisodeShift``)."""

    env: Cell

    @property
    def model(self) -> mujoco.MjModel: ...

    def generator(self, *key: str) -> np.random.Generator: ...

    def on_image(self, effect: Callable[[str, np.ndarray], np.ndarray]) -> None: ...

    def on_action(self, effect: Callable[[np.ndarray], np.ndarray]) -> None: ...

    def on_spawn(self, edit: Callable[[Spawn], Spawn]) -> None: ...


class Shift(ABC):
    """One factor.

    Attributes:
        name: the command-line name, e.g. ``camera-pose``.
        group: one of ``GROUPS``.
        summary: one line: what changes.
        unit: how a level reads, a format string of its magnitude(s), e.g. ``"{} cm moved, {} deg turned"``.
        magnitudes: what levels 1, 2 and 3 set, in the units ``unit`` names (level 0 is the cell as built).
        as_built: the magnitude of the cell as built, where it is not zero (``box-mass``: 0.5 kg, friction 1.0).
        trainable: whether ``NAME:train`` exists: False where no value lies between the cell and level 1
            (``action-delay``: whole control steps), or where a blur's smallest kernel is level 1's, or for the
            shifts every recipe leaves wholly unseen (``box-shape``, ``novel-distractors``).
    """

    name: ClassVar[str]
    group: ClassVar[str]
    summary: ClassVar[str]
    unit: ClassVar[str]
    magnitudes: ClassVar[tuple[Any, Any, Any]]
    as_built: ClassVar[Any] = None
    trainable: ClassVar[bool] = True

    def magnitude(self, level: float) -> Any:
        """What ``level`` sets, in ``unit``: levels 1-3 as ``magnitudes`` says; a fraction in [0, 1) (a training
        draw) that fraction of the way from ``as_built`` to level 1, numbers interpolated, names (a texture) kept
        as level 1's."""
        if level >= 1:
            return self.magnitudes[int(level) - 1]
        if not self.trainable:
            raise ValueError(f"shift {self.name!r} has no training range")
        return between(self.as_built, self.magnitudes[0], level)

    def level_text(self, level: int) -> str:
        """Level ``level`` for ``--list-shifts``."""
        if level == 0:
            return "as built"
        m = self.magnitude(level)
        return self.unit.format(*(m if isinstance(m, tuple) else (m,)))

    def draw(self, level: float, rng: np.random.Generator) -> dict[str, Any]:
        """This episode's values at ``level`` (1-3, or a training fraction), JSON-ready: what ``apply`` sets,
        recorded with the episode. By default nothing: a shift with no direction and no choice applies its level's
        magnitude."""
        return {}

    @abstractmethod
    def apply(self, episode: Episode, level: float, drawn: dict[str, Any], rng: np.random.Generator) -> None:
        """Change the cell at reset as ``drawn`` says; ``rng`` (the shift's own) for draws during the episode."""


def between(start: Any, end: Any, fraction: float) -> Any:
    """``fraction`` of the way from ``start`` (None: zero) to ``end``: tuples element by element, names as ``end``."""
    if isinstance(end, tuple):
        starts = start if isinstance(start, tuple) else (start,) * len(end)
        return tuple(between(a, b, fraction) for a, b in zip(starts, end, strict=True))
    if isinstance(end, str):
        return end
    a = 0.0 if start is None else float(start)
    return a + fraction * (float(end) - a)


def unit_vector(rng: np.random.Generator, n: int = 3) -> np.ndarray:
    """A direction drawn uniformly on the unit sphere in ``n`` dimensions."""
    v = rng.normal(size=n)
    return v / np.linalg.norm(v)


def rounded(values: Any, digits: int = 4) -> Any:
    """Floats (or arrays of them) rounded for a JSON record."""
    return np.round(np.asarray(values, float), digits).tolist()
