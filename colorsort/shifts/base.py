"""What a held-out shift is: a factor of the cell with levels 0 to 3 in physical units.

A ``Shift`` draws its values for an episode (``draw``: a direction, a sign, a choice) from the episode's own
generator and applies them to the cell (``apply``) at reset, through an ``EpisodeShift`` (``episode.py``): the
model (cameras, lights, materials, masses), the pool's palette and box style, the belt's speed, the arm's start,
and three hooks for what happens later in the episode (each new box, each rendered image, each action).
Level 0 is no change; a shift never runs at level 0. Shifts are for evaluation only: no recipe trains on a
held-out level (``docs/shifts.md``).
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
GROUPS: tuple[str, ...] = ("viewpoint", "appearance", "objects", "dynamics", "layout")


class Cell(Protocol):
    """What shifts reach of a ``Cell`` env (``cell/env.py``): its model and data, plant, arm and settings."""

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
    """

    name: ClassVar[str]
    group: ClassVar[str]
    summary: ClassVar[str]
    unit: ClassVar[str]
    magnitudes: ClassVar[tuple[Any, Any, Any]]

    def magnitude(self, level: int) -> Any:
        """What ``level`` (1-3) sets, in ``unit``."""
        return self.magnitudes[level - 1]

    def level_text(self, level: int) -> str:
        """Level ``level`` for ``--list-shifts``."""
        if level == 0:
            return "as built"
        m = self.magnitude(level)
        return self.unit.format(*(m if isinstance(m, tuple) else (m,)))

    def draw(self, level: int, rng: np.random.Generator) -> dict[str, Any]:
        """This episode's values at ``level`` (1-3), JSON-ready: what ``apply`` sets, recorded with the episode.
        By default nothing: a shift with no direction and no choice applies its level's magnitude."""
        return {}

    @abstractmethod
    def apply(self, episode: Episode, level: int, drawn: dict[str, Any], rng: np.random.Generator) -> None:
        """Change the cell at reset as ``drawn`` says; ``rng`` (the shift's own) for draws during the episode."""


def unit_vector(rng: np.random.Generator, n: int = 3) -> np.ndarray:
    """A direction drawn uniformly on the unit sphere in ``n`` dimensions."""
    v = rng.normal(size=n)
    return v / np.linalg.norm(v)


def rounded(values: Any, digits: int = 4) -> Any:
    """Floats (or arrays of them) rounded for a JSON record."""
    return np.round(np.asarray(values, float), digits).tolist()
