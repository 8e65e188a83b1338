"""The conveyor: the belt drive with its ray sensor, and the spawner that puts boxes on the belt.

The belt is a box geom on a slide joint along x (``models/arena.py``). Before every physics step
the drive sets the joint's velocity to the belt speed and its position back to 0, so the surface
never travels but every contact sees it moving: boxes resting on it are carried by friction.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np

from colorsort.cell.boxes import Box, BoxPool
from colorsort.config import BoxStyle, CellLayout, TaskConfig


class Belt:
    """Runs the belt from the ray sensor and the belt-pass command, once per physics step.

    On a stopping belt (the original cell) the ray stops the belt while it sees a box; on a
    tracking belt (``TaskConfig.tracking``) the belt never stops and the ray only reports.

    Attributes:
        running: the belt moves (tracking, the ray is clear, or the belt-pass command is on).
        box_detected: the ray sees something within its range.
        belt_pass: the command to run the belt even while the ray is blocked (how a box with no
            bin is let through).
        travel: [m] the distance the belt surface has travelled this episode: its encoder.
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, layout: CellLayout, speed: float,
                 tracking: bool = False):
        self.data, self.layout, self.speed, self.tracking = data, layout, speed, tracking
        self.timestep = float(model.opt.timestep)  # [s] one physics step
        joint = model.joint("belt_slide").id
        self.qpos, self.qvel = model.jnt_qposadr[joint], model.jnt_dofadr[joint]
        self.ray = model.sensor_adr[model.sensor("ray").id]
        self.reset()

    def reset(self) -> None:
        """Belt at rest in its place, running, nothing seen, no pass command."""
        self.data.qpos[self.qpos] = 0.0
        self.data.qvel[self.qvel] = 0.0
        self.running, self.box_detected, self.belt_pass = True, False, False
        self.travel = 0.0

    def get_state(self) -> tuple[bool, bool, float]:
        """(belt-pass command, running, travel [m]); the slide joint is MuJoCo's state."""
        return self.belt_pass, self.running, self.travel

    def set_state(self, belt_pass: bool, running: bool, travel: float) -> None:
        self.belt_pass, self.running, self.travel = belt_pass, running, travel

    def sense(self) -> bool:
        """Read the ray (from the last computed sensor data) into ``box_detected``."""
        distance = self.data.sensordata[self.ray]
        self.box_detected = bool(0.0 <= distance <= self.layout.sensor_range)
        return self.box_detected

    def drive(self) -> None:
        """Run or stop the belt from the ray and the pass command for the coming physics step; hold the
        surface in place and count its travel."""
        self.sense()
        self.running = self.tracking or self.belt_pass or not self.box_detected
        self.data.qpos[self.qpos] = 0.0
        self.data.qvel[self.qvel] = -self.speed if self.running else 0.0
        if self.running:
            self.travel += self.speed * self.timestep


@dataclass(frozen=True)
class Spawn:
    """What the spawner drew for a new box: colour, offset from the centre line [m], yaw [rad], style (None: the
    pool's). A held-out shift (``colorsort.shifts``) may change it before the box is set down."""

    color: str
    offset: float
    yaw: float
    style: BoxStyle | None = None


@dataclass(frozen=True)
class Placement:
    """Where a box was set down on the belt."""

    serial: int
    color: str
    offset: float  # [m] from the belt's centre line, + toward the bins
    yaw: float  # [deg] about z


class Spawner:
    """A box from the pool every ``spawn_period`` [s] at the belt's upstream end.

    Colour drawn from ``box_colors``, optional lateral and yaw jitter, all from the generator it is
    given; it waits while the pool is empty or the spawn point is occupied.

    Attributes:
        next_time: [s] sim time of the next spawn.
        next_serial: the serial the next box gets.
        placed: every box set down since the reset, in order (like the referee's events, a record of the
            episode, not part of the sim state).
        edit: what a held-out shift makes of each draw, or None (``colorsort.shifts``); it draws from its own
            generator, so the env's generator gives the same box stream with or without it.
    """

    def __init__(self, pool: BoxPool, config: TaskConfig):
        self.pool, self.config = pool, config
        self.edit: Callable[[Spawn], Spawn] | None = None
        self.reset()

    def reset(self) -> None:
        self.next_time, self.next_serial = 0.0, 0
        self.placed: list[Placement] = []

    def get_state(self) -> tuple[float, int]:
        """(next spawn time [s], next serial)."""
        return self.next_time, self.next_serial

    def set_state(self, next_time: float, next_serial: int) -> None:
        self.next_time, self.next_serial = next_time, next_serial

    def put(self, box: Box, color: str, x: float, y: float, yaw: float, style: BoxStyle | None = None) -> None:
        """Set ``box`` down on the belt at (x, y) [m], turned ``yaw`` [rad], with the next serial."""
        self.pool.place(box, color, x, y, yaw, self.next_serial, style)
        offset = float(y - self.pool.layout.belt_y)
        self.placed.append(Placement(self.next_serial, color, offset, float(np.rad2deg(yaw))))
        self.next_serial += 1

    def spawn_if_due(self, now: float, rng: np.random.Generator) -> Box | None:
        """Spawn a box if one is due at sim time ``now`` [s], the pool has one and the spot is free."""
        if now + 1e-9 < self.next_time:
            return None
        parked = self.pool.parked()
        if not parked or not self.pool.spawn_point_clear():
            return None  # wait: try again next step
        L, cfg = self.pool.layout, self.config
        box = parked[0]
        color = str(rng.choice(cfg.box_colors))
        dy = rng.uniform(-cfg.lateral_jitter, cfg.lateral_jitter)
        yaw = np.deg2rad(rng.uniform(-cfg.yaw_jitter, cfg.yaw_jitter))
        if self.edit is None:
            self.put(box, color, L.spawn_x, L.belt_y + dy, yaw)
        else:
            s = self.edit(Spawn(color, float(dy), float(yaw)))
            self.put(box, s.color, L.spawn_x, L.belt_y + s.offset, s.yaw, s.style)
        self.next_time = now + cfg.spawn_period
        return box
