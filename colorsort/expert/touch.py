"""The touch-off: a guarded descent onto a box whose height the expert does not know.

A real vacuum cup's controller reports *part present* when the vacuum crosses its threshold, and a
pick comes down slowly over the last centimetres until it does; the heights come from that touch, not
from a calibration of one box size. The expert does the same with the cell's vacuum switch
(``suction_sealed``): fast to ``touch_clearance`` over the tallest box the cell accepts
(``CellLayout.tallest_box``), then straight down at ``touch_speed`` with suction on, to a floor
``touch_floor`` under the top of the lowest box the cell accepts (``CellLayout.shortest_box``). It
stops when the switch reports a seal; at the floor with none it backs off. At 20 Hz the switch is read
once a control period, so the reference runs on at most ``touch_speed`` times that period past the
touch before the stop begins: the speed is what bounds the press.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from colorsort.config import CellLayout
from colorsort.expert.planning import CupIK, DensePath, Waypoint


@dataclass(frozen=True)
class Descent:
    """Where a touch-off starts and where it gives up, as cup heights [m]."""

    start: float  # over the tallest box the cell accepts
    floor: float  # under the top of the lowest

    @classmethod
    def of(cls, layout: CellLayout, clearance: float, floor: float) -> Descent:
        """The descent for ``layout``, ``clearance`` [m] over its tallest box and ``floor`` [m] under its lowest."""
        return cls(layout.belt_top_z + layout.tallest_box + clearance, layout.belt_top_z + layout.shortest_box - floor)

    def duration(self, speed: float) -> float:
        """[s] from the start to the floor at ``speed`` [m/s]."""
        return (self.start - self.floor) / speed


def straight_path(ik: CupIK, start: tuple[float, float, float], velocity: tuple[float, float, float], yaw: float,
                  duration: float, dt: float, q_seed: np.ndarray) -> DensePath:
    """The cup moving in a straight line from ``start`` [m] at a constant ``velocity`` [m/s], facing down turned
    ``yaw`` [rad], for ``duration`` [s]: joint angles every control period ``dt`` [s], each IK warm-started from the
    one before (the first from ``q_seed``).

    Raises:
        UnreachableWaypoint: a point on the way is out of reach.
    """
    steps = int(np.ceil(duration / dt - 1e-9))
    p0, v = np.asarray(start, float), np.asarray(velocity, float)
    q, path = q_seed, []
    for k in range(steps + 1):
        q = ik.solve(Waypoint("touch-off", tuple(p0 + v * (k * dt)), yaw), q)
        path.append(q)
    return DensePath(np.array(path), dt)
