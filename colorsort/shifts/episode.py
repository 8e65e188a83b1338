"""An env's held-out shifts (``CellShifts``) and one episode's (``EpisodeShift``): the model restored as built, then
each shift drawn and applied.

``ColorSort`` (``envs/robosuite_task.py``) holds a ``CellShifts``, whose ``begin`` restores the cell and builds an
``EpisodeShift`` at every reset, after robosuite reset the arm and before the first box is spawned; the env then
passes each new box (``edit_spawn``), each rendered image (``image``) and each action (``action``) through it.
Every shift draws from its own generator, seeded from the episode's seed and the shift's name, so a shift draws the
same values alone or with others, and the env's own generator (the box stream, the lights) draws exactly as
without shifts.
"""

from __future__ import annotations

import zlib
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from colorsort.config import ALL_COLORS
from colorsort.shifts.base import TRAIN, Cell
from colorsort.shifts.registry import SHIFTS, ShiftLevel, parse_shifts

if TYPE_CHECKING:
    from colorsort.cell.conveyor import Spawn


# The model's fields a shift may change: saved as compiled, restored before every shifted episode.
MODEL_FIELDS = ("cam_pos", "cam_quat", "light_pos", "light_dir", "mat_rgba", "geom_matid", "geom_rgba",
                "geom_friction", "body_mass", "body_inertia")


class AsBuilt:
    """The values of ``MODEL_FIELDS`` of one compiled model, as it was built."""

    def __init__(self, model: mujoco.MjModel):
        self.model = model
        self.values = {f: getattr(model, f).copy() for f in MODEL_FIELDS}

    def restore(self, fields: tuple[str, ...] = MODEL_FIELDS) -> None:
        for f in fields:
            getattr(self.model, f)[:] = self.values[f]


def restore_cell(env: Cell, built: AsBuilt) -> None:
    """Undo every shift: the model's fields, the pool's palette and box styles, the belt's speed, the lights'
    colour, the spawner's and the cameras' hooks."""
    pool = env.plant.pool
    for box in pool.boxes:
        pool.shape(box, None)
    built.restore()
    pool.palette, pool.style = dict(ALL_COLORS), None
    env.plant.belt.speed = env.config.belt_speed
    env.plant.spawner.edit = None
    env.plant.lights.tint = np.ones(3)
    env.plant.lights.apply(env.plant.lighting)


def shift_seed(rng: np.random.Generator) -> int:
    """A seed for an episode's shifts, read from a copy of the env's generator: the original draws nothing."""
    copy = np.random.Generator(type(rng.bit_generator)())
    copy.bit_generator.state = rng.bit_generator.state
    return int(copy.integers(2**63))


class CellShifts:
    """The held-out shifts of one env, applied afresh at every reset (``begin``); empty: the cell as built.

    Attributes:
        shifts: the shifts above level 0, in the registry's order.
        episode: this episode's ``EpisodeShift`` (None before the first reset, or with no shift).
    """

    def __init__(self, shift: str | Iterable[str] | None):
        self.shifts: tuple[ShiftLevel, ...] = tuple(s for s in parse_shifts(shift) if s.active)
        self.episode: EpisodeShift | None = None
        self._built: AsBuilt | None = None

    def __bool__(self) -> bool:
        return bool(self.shifts)

    def begin(self, env: Cell) -> EpisodeShift:
        """Undo the last episode's shifts, then draw and apply this one's (after the arm's reset, before the first
        box); returns what the cameras and the actions go through."""
        if self._built is None or self._built.model is not env.mj_model:
            self._built = AsBuilt(env.mj_model)
        restore_cell(env, self._built)
        self.episode = EpisodeShift(env, self._built, self.shifts, shift_seed(env.rng))
        return self.episode

    def undo(self, env: Cell) -> None:
        """Put the cell back as built (before its shifts change)."""
        if self.episode is not None and self._built is not None:
            restore_cell(env, self._built)
        self.episode = None

    def action(self, action: np.ndarray) -> np.ndarray:
        return action if self.episode is None else self.episode.action(action)

    @property
    def record(self) -> dict[str, dict[str, Any]]:
        return dict(self.episode.drawn) if self.episode is not None else {}

    @contextmanager
    def cameras_as_built(self) -> Iterator[None]:
        if self.episode is None:
            yield
        else:
            with self.episode.cameras_as_built():
                yield


class EpisodeShift:
    """Shifts drawn and applied to the env's cell for one episode.

    Attributes:
        env: the ``Cell`` env.
        drawn: per shift name, its level and the values drawn for this episode (what ``--json`` records).
    """

    def __init__(self, env: Cell, built: AsBuilt, shifts: tuple[ShiftLevel, ...], seed: int):
        self.env, self.built, self.seed = env, built, seed
        self.drawn: dict[str, dict[str, Any]] = {}
        self._images: list[Callable[[str, np.ndarray], np.ndarray]] = []
        self._actions: list[Callable[[np.ndarray], np.ndarray]] = []
        self._spawns: list[Callable[[Spawn], Spawn]] = []
        for s in shifts:
            if not s.active:
                continue
            shift, rng = SHIFTS[s.name], self.generator(s.name)
            level = float(rng.uniform()) if s.level == TRAIN else int(s.level)  # training: a fraction of level 1
            drawn = shift.draw(level, rng)
            self.drawn[s.name] = {"level": s.level, **({"fraction": round(level, 4)} if s.level == TRAIN else {}),
                                  **drawn}
            shift.apply(self, level, drawn, rng)
        if self._spawns:
            env.plant.spawner.edit = self.edit_spawn

    @property
    def model(self) -> mujoco.MjModel:
        return self.env.mj_model

    def generator(self, *key: str) -> np.random.Generator:
        """A generator of this episode for ``key`` (a shift's name, then e.g. a camera and its size)."""
        return np.random.default_rng([self.seed, *(zlib.crc32(k.encode()) for k in key)])

    # ------------------------------------------------------------------ hooks a shift installs
    def on_image(self, effect: Callable[[str, np.ndarray], np.ndarray]) -> None:
        """``effect(camera, image)`` on every image a camera renders this episode ((H, W, 3) uint8)."""
        self._images.append(effect)

    def on_action(self, effect: Callable[[np.ndarray], np.ndarray]) -> None:
        """``effect(action)`` on every action before the cell applies it."""
        self._actions.append(effect)

    def on_spawn(self, edit: Callable[[Spawn], Spawn]) -> None:
        """``edit(spawn)`` on every box the spawner draws, before it is set down."""
        self._spawns.append(edit)

    # ------------------------------------------------------------------ what the env calls
    def image(self, camera: str, image: np.ndarray) -> np.ndarray:
        for effect in self._images:
            image = effect(camera, image)
        return image

    def action(self, action: np.ndarray) -> np.ndarray:
        for effect in self._actions:
            action = effect(action)
        return action

    def edit_spawn(self, spawn: Spawn) -> Spawn:
        for edit in self._spawns:
            spawn = edit(spawn)
        return spawn

    @contextmanager
    def cameras_as_built(self) -> Iterator[None]:
        """The cameras where the cell was built (and calibrated) for the duration: the expert calibrates here."""
        m, d = self.model, self.env.mj_data
        shifted = m.cam_pos.copy(), m.cam_quat.copy()
        self.built.restore(("cam_pos", "cam_quat"))
        _place_cameras(m, d)
        try:
            yield
        finally:
            m.cam_pos[:], m.cam_quat[:] = shifted
            _place_cameras(m, d)


def _place_cameras(m: mujoco.MjModel, d: mujoco.MjData) -> None:
    """Recompute the cameras' world poses from the model and the joints, nothing else."""
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    mujoco.mj_camlight(m, d)
