"""The box pool: boxes allocated once in the model, parked below the floor until they are needed.

A parked box has collisions off and gravity compensated; ``place`` brings one to the belt and
``park`` returns it. The pool keeps each box's bookkeeping (colour, status, bin, serial) and
reads poses from MuJoCo's data.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import mujoco
import numpy as np

from colorsort.cell.models.arena import park_position
from colorsort.config import ALL_COLORS, BIN_COLORS, BoxStyle, CellLayout

SPAWN_GAP = 0.002  # [m] a box is set down this far above the belt
SPAWN_CLEAR = 1.5  # box sizes along the belt the spawn point must be clear of boxes in play


class BoxStatus(Enum):
    """Where a pooled box is. The order is part of the sim state (``sim_state.py``): append only."""

    PARKED = "parked"  # in the pool, out of sight
    IN_PLAY = "in_play"  # on the belt, in the cup or in the air
    IN_BIN = "in_bin"  # resting in a bin, any bin


@dataclass
class Box:
    """Bookkeeping for one pooled box."""

    index: int
    status: BoxStatus = BoxStatus.PARKED
    color: str = "red"
    bin: str | None = None
    serial: int = -1  # 0, 1, 2, ... in order of appearance this episode; -1 while parked


class BoxPool:
    """``size`` boxes named ``box0``, ``box1``, ... in a compiled model.

    Args:
        model, data: the compiled MuJoCo model and its data.
        size: boxes in the pool.
        layout: the cell's geometry (belt height, box size).
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, size: int, layout: CellLayout):
        self.model, self.data, self.layout = model, data, layout
        self.boxes = [Box(i) for i in range(size)]
        self.body = [model.body(f"box{i}").id for i in range(size)]
        self.geom = [model.geom(f"box{i}_geom").id for i in range(size)]
        self.qpos = [model.jnt_qposadr[model.joint(f"box{i}_joint").id] for i in range(size)]
        self.qvel = [model.jnt_dofadr[model.joint(f"box{i}_joint").id] for i in range(size)]
        # What a held-out shift (``colorsort.shifts``) may change for an episode: the colour of each name, the
        # style of every new box (None: the cube the model was compiled with); ``place`` may give one its own.
        self.palette: dict[str, tuple[float, ...]] = dict(ALL_COLORS)
        self.style: BoxStyle | None = None
        self._styled: list[BoxStyle | None] = [None] * size
        self._compiled = [(int(model.geom_type[g]), model.geom_size[g].copy(), float(model.geom_rbound[g]),
                           model.geom_aabb[g].copy(), model.body_inertia[b].copy())
                          for g, b in zip(self.geom, self.body, strict=True)]

    def in_play(self) -> list[Box]:
        """Boxes on the belt, in the cup or in the air."""
        return [b for b in self.boxes if b.status is BoxStatus.IN_PLAY]

    def parked(self) -> list[Box]:
        return [b for b in self.boxes if b.status is BoxStatus.PARKED]

    def in_bin(self, color: str) -> list[Box]:
        """Boxes resting in the bin of ``color``."""
        return [b for b in self.boxes if b.status is BoxStatus.IN_BIN and b.bin == color]

    def pos(self, box: Box) -> np.ndarray:
        """World position of a box's centre [m], (3,)."""
        return self.data.xpos[self.body[box.index]].copy()

    def pose(self, box: Box) -> np.ndarray:
        """A box's free-joint pose: centre [m] then quaternion (w, x, y, z), (7,)."""
        qa = self.qpos[box.index]
        return self.data.qpos[qa : qa + 7].copy()

    def speed(self, box: Box) -> float:
        """A box's linear speed [m/s]."""
        va = self.qvel[box.index]
        return float(np.linalg.norm(self.data.qvel[va : va + 3]))

    def park(self, box: Box) -> None:
        """Return a box to the pool: below the floor, collisions off, gravity compensated."""
        qa, va = self.qpos[box.index], self.qvel[box.index]
        self.data.qpos[qa : qa + 7] = (*park_position(box.index), 1.0, 0.0, 0.0, 0.0)
        self.data.qvel[va : va + 6] = 0.0
        self.set_collidable(box, False)
        self.model.body_gravcomp[self.body[box.index]] = 1.0
        box.status, box.bin, box.serial = BoxStatus.PARKED, None, -1

    def height(self, box: Box) -> float:
        """[m] how tall a box stands."""
        style = self._styled[box.index]
        return self.layout.box_size if style is None else style.height

    def place(self, box: Box, color: str, x: float, y: float, yaw: float, serial: int,
              style: BoxStyle | None = None) -> None:
        """Set a parked box down on the belt, centred at (x, y) [m], turned ``yaw`` [rad], ``SPAWN_GAP`` up; shaped as
        ``style``, else the pool's ``style``."""
        self.shape(box, style or self.style)
        qa, va = self.qpos[box.index], self.qvel[box.index]
        z = self.layout.belt_top_z + self.height(box) / 2 + SPAWN_GAP
        self.data.qpos[qa : qa + 7] = (x, y, z, np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2))
        self.data.qvel[va : va + 6] = 0.0
        self.paint(box, color)
        self.set_collidable(box, True)
        self.model.body_gravcomp[self.body[box.index]] = 0.0
        box.status, box.bin, box.serial = BoxStatus.IN_PLAY, None, serial

    def paint(self, box: Box, color: str) -> None:
        box.color = color
        self.model.geom_rgba[self.geom[box.index]] = self.palette[color]

    def shape(self, box: Box, style: BoxStyle | None) -> None:
        """Give a box the geometry (and the inertia, at its body's mass) of ``style``; None: as compiled."""
        if style == self._styled[box.index]:
            return
        m, g, b = self.model, self.geom[box.index], self.body[box.index]
        if style is None:
            kind, size, rbound, aabb, inertia = self._compiled[box.index]
            m.geom_type[g], m.geom_size[g], m.geom_rbound[g], m.geom_aabb[g], m.body_inertia[b] = (
                kind, size, rbound, aabb, inertia)
        else:
            kind, size, rbound, half = style.geometry()
            m.geom_type[g], m.geom_size[g], m.geom_rbound[g] = kind, size, rbound
            m.geom_aabb[g] = (0.0, 0.0, 0.0, *half)
            m.body_inertia[b] = style.inertia(float(m.body_mass[b]))
        self._styled[box.index] = style

    def set_collidable(self, box: Box, on: bool) -> None:
        # MuJoCo's broad phase also filters on the per-body OR of its geoms' bits: set both.
        m, flag = self.model, int(on)
        for arr, idx in ((m.geom_contype, self.geom), (m.geom_conaffinity, self.geom),
                         (m.body_contype, self.body), (m.body_conaffinity, self.body)):
            arr[idx[box.index]] = flag

    def restore(self, box: Box, status: BoxStatus) -> None:
        """Collisions and gravity as ``status`` has them (after a sim state was set)."""
        self.set_collidable(box, status is not BoxStatus.PARKED)
        self.model.body_gravcomp[self.body[box.index]] = float(status is BoxStatus.PARKED)

    def get_state(self) -> np.ndarray:
        """(pool size, 4) int, per box: colour (index in ``config.ALL_COLORS``, -1 while parked), status (index in
        ``BoxStatus``), bin (index in ``BIN_COLORS``, -1 for none), serial. Poses are MuJoCo's state."""
        colors, statuses = list(ALL_COLORS), list(BoxStatus)
        return np.array([(colors.index(b.color) if b.status is not BoxStatus.PARKED else -1, statuses.index(b.status),
                          BIN_COLORS.index(b.bin) if b.bin is not None else -1, b.serial) for b in self.boxes])

    def set_state(self, state: np.ndarray) -> None:
        """Every box as ``get_state`` saved it: bookkeeping, colour, collisions and gravity."""
        colors, statuses = list(ALL_COLORS), list(BoxStatus)
        for box, (color, status, bin_index, serial) in zip(self.boxes, state, strict=True):
            box.status, box.serial = statuses[status], int(serial)
            box.bin = BIN_COLORS[bin_index] if bin_index >= 0 else None
            if color >= 0:  # a parked box's colour is whatever it last had: out of sight, not part of the state
                self.paint(box, colors[color])
            self.restore(box, box.status)

    def spawn_point_clear(self) -> bool:
        """No box in play within ``SPAWN_CLEAR`` box sizes of the spawn point along the belt."""
        L = self.layout
        size = max(L.box_size, self.style.width if self.style is not None else 0.0)
        for box in self.in_play():
            x, y, _ = self.pos(box)
            if abs(x - L.spawn_x) < SPAWN_CLEAR * size and abs(y - L.belt_y) < L.belt_width:
                return False
        return True
