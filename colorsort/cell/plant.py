"""The plant: the cell's machinery wired to one compiled model, robosuite aside.

The box pool, the belt with its ray sensor, the spawner, the vacuum seal, the lights and the
referee, stepped together: ``physics_step`` before every MuJoCo step, ``control_step`` at the end
of every control period. ``ColorSort`` (``env.py``) is the robosuite glue around it. Each part
owns its state (``get_state``/``set_state``); ``Plant.get_state`` gathers them with MuJoCo's.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from colorsort.cell.boxes import Box, BoxPool
from colorsort.cell.conveyor import Belt, Spawner
from colorsort.cell.lighting import LightRig
from colorsort.cell.observation import BOX_STATE
from colorsort.cell.referee import Referee
from colorsort.cell.suction import VacuumSeal
from colorsort.config import BIN_COLORS, COLORS, CellLayout, Lighting, TaskConfig
from colorsort.errors import PlanningError, UnknownName

# The parts of MuJoCo's state that ColorSort changes while it runs.
MJ_STATE_SPEC = (mujoco.mjtState.mjSTATE_FULLPHYSICS | mujoco.mjtState.mjSTATE_CTRL | mujoco.mjtState.mjSTATE_EQ_ACTIVE
                 | mujoco.mjtState.mjSTATE_MOCAP_POS | mujoco.mjtState.mjSTATE_MOCAP_QUAT
                 | mujoco.mjtState.mjSTATE_WARMSTART)


@dataclass(frozen=True)
class Grip:
    """How the cup held a box when it sealed on it (``VacuumSeal.grip``)."""

    serial: int
    offset: float  # [m] the box centre's distance from the cup axis
    yaw: float  # [deg] the box's turn against the cup, in [-45, 45)


@dataclass
class PlantState:
    """The plant's part of an instant (``sim_state.py`` lays it out as a vector)."""

    mujoco: np.ndarray  # (mj_stateSize(MJ_STATE_SPEC),) MuJoCo's state
    boxes: np.ndarray  # (pool size, 4) int: ``BoxPool.get_state``
    held: int  # the sealed box's pool index, or -1
    weld: np.ndarray  # (mjNEQDATA,) the seal's weld
    belt_pass: bool
    belt_running: bool
    belt_travel: float  # [m] the belt's encoder
    next_spawn_time: float  # [s]
    next_serial: int


class Plant:
    """Pool, belt, spawner, seal, lights and referee of one compiled model.

    Args:
        model, data: the compiled MuJoCo model and its data.
        layout: the cell's geometry [m].
        config: the task's parameters.
        cup, pad, suction: the gripper's cup body, pad geom and suction actuator, as compiled.
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, layout: CellLayout, config: TaskConfig,
                 cup: str, pad: str, suction: str):
        self.model, self.data = model, data
        self.pool = BoxPool(model, data, config.pool_size, layout)
        self.belt = Belt(model, data, layout, config.belt_speed, config.tracking)
        self.spawner = Spawner(self.pool, config)
        self.referee = Referee(layout, config.bin_capacity)
        names = [f"box{i}" for i in range(config.pool_size)]
        self.seal = VacuumSeal(model, data, cup_body=cup, pad_geom=pad, actuator=suction, box_bodies=names,
                               box_geoms=[f"{n}_geom" for n in names], welds=[f"suction_{n}" for n in names])
        self.lights = LightRig(model)
        self.lighting = Lighting()
        self.grips: list[Grip] = []  # every seal of this episode, in order

    def reset(self, now: float, rng: np.random.Generator) -> None:
        """Every box back in the pool, the belt at rest and running, counters cleared, the first box spawned."""
        self.referee.reset()
        self.spawner.reset()
        self.grips = []
        for box in self.pool.boxes:
            self.remove_box(box)
        self.belt.reset()
        self.spawn_if_due(now, rng)

    def get_state(self) -> PlantState:
        """This instant of the plant: MuJoCo's state and every part's."""
        mj = np.empty(mujoco.mj_stateSize(self.model, MJ_STATE_SPEC))
        mujoco.mj_getState(self.model, self.data, mj, MJ_STATE_SPEC)
        held, weld = self.seal.get_state()
        belt_pass, running, travel = self.belt.get_state()
        next_time, next_serial = self.spawner.get_state()
        return PlantState(mj, self.pool.get_state(), held, weld, belt_pass, running, travel, next_time, next_serial)

    def set_state(self, s: PlantState) -> None:
        """Back to the instant ``get_state`` saved; derived quantities (positions, sensors, the ray) recomputed."""
        mujoco.mj_setState(self.model, self.data, s.mujoco, MJ_STATE_SPEC)
        self.pool.set_state(s.boxes)
        self.seal.set_state(s.held, s.weld)
        self.belt.set_state(s.belt_pass, s.belt_running, s.belt_travel)
        self.spawner.set_state(s.next_spawn_time, s.next_serial)
        mujoco.mj_forward(self.model, self.data)
        self.belt.sense()

    def physics_step(self) -> None:
        """Before each MuJoCo step, after the controller wrote ``ctrl``: drive the belt, seal or release."""
        self.belt.drive()
        was = self.seal.held
        self.seal.update()
        if self.seal.held is not None and self.seal.held != was:
            self.grips.append(Grip(self.pool.boxes[self.seal.held].serial, *self.seal.grip()))

    def control_step(self, now: float, rng: np.random.Generator) -> float:
        """At the end of a control period (sim time ``now`` [s]): judge the boxes, spawn. Returns the
        period's sparse reward."""
        reward = self.referee.update(self.pool, now, self.remove_box)
        self.spawn_if_due(now, rng)
        return reward

    def spawn_if_due(self, now: float, rng: np.random.Generator) -> None:
        if self.spawner.spawn_if_due(now, rng) is not None:
            self.referee.tally.spawned += 1

    def put_box(self, color: str, x: float, y: float, yaw: float = 0.0) -> Box:
        """Take a box from the pool and set it down on the belt at (x, y) [m], turned ``yaw`` [rad]."""
        if color not in COLORS:
            raise UnknownName("colour", color, sorted(COLORS), "colours")
        parked = self.pool.parked()
        if not parked:
            raise PlanningError(f"All {len(self.pool.boxes)} boxes of the pool are in play")
        self.spawner.put(parked[0], color, x, y, yaw)
        return parked[0]

    def remove_box(self, box: Box) -> None:
        """Return a box to the pool at once (the cup lets go of it first); no outcome is recorded."""
        self.seal.release(box.index)
        self.pool.park(box)

    def set_lighting(self, lighting: Lighting) -> None:
        self.lights.apply(lighting)
        self.lighting = lighting

    def next_box_state(self) -> np.ndarray:
        """The in-play box with the lowest serial: colour one-hot over ``config.COLORS``, pose (7,)
        (centre [m], quaternion w, x, y, z), then 1.0; zeros when no box is in play. Shape (len(COLORS) + 8,)."""
        boxes = self.pool.in_play()
        if not boxes:
            return BOX_STATE.pack(None, None)
        box = min(boxes, key=lambda b: b.serial)
        # a novel distractor (``config.NOVEL_COLORS``) has no class: no one-hot
        return BOX_STATE.pack(list(COLORS).index(box.color) if box.color in COLORS else None, self.pool.pose(box))

    def staged_rewards(self) -> dict[str, float]:
        return self.referee.staged_rewards(self.pool, self.data.geom_xpos[self.seal.pad], self.seal.held)

    def info(self, boxes_to_sort: int) -> dict[str, Any]:
        """The counters ``ColorSort.step`` reports in ``info``."""
        t = self.referee.tally
        bins = {color: [b.color == color for b in self.pool.in_bin(color)] for color in BIN_COLORS}
        return {
            "belt_running": self.belt.running,
            "belt_travel": self.belt.travel,
            "box_detected": self.belt.box_detected,
            "placed": dict(t.placed),
            "misplaced": t.misplaced,
            "dropped": t.dropped,
            "rejected": t.rejected,
            "bins_emptied": t.bins_emptied,
            "spawned": t.spawned,
            "bins": {c: {"count": len(m), "matches": m} for c, m in bins.items()},
            "suction_sealed": self.seal.held is not None,
            "is_success": t.success(boxes_to_sort),
        }
