"""The scripted sorting expert: the original cell's phases as a state machine.

It acts only on what a real cell has: the ray sensor (``box_detected``), the colour camera
(``sensor_image``, or a photo it triggers when the ray fires if the env does not render that
camera every step), the arm's joint angles (``robot0_joint_pos``) and the cup's vacuum switch
(``suction_sealed``). Waypoints come from mink IK, motions from ruckig (``planning.py``).

Phases (the original's numbering):

1. ``MOVE_TO_WAIT``: move to the wait pose, beside and above the pick point, out of the camera's view;
2. ``WAIT_FOR_BOX``: hold until the ray sees a box, then look: a box of a bin colour is picked,
   any other (or none seen) is let through (``LET_PASS``: belt-pass on until the ray clears);
3. ``DESCEND``: over the box where the camera saw it, cup turned to its yaw, then down onto it;
4. ``GRIP``: suction on until the vacuum switch reports a seal;
5. ``BACK_UP``: straight up;
6. ``MOVE_OVER_BIN``: to the next drop slot over the bin of the colour seen;
7. ``RELEASE``: suction off until the seal is gone and the box has fallen clear;
8. emptying full bins is the cell's own job here: ``ColorSort`` empties a bin when it is full.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from colorsort.config import BIN_COLORS, ROBOT_JOINT_SPEEDS
from colorsort.env import ColorSort
from colorsort.perception import CameraModel, ColorSensor, Detection, PerceptionConfig
from colorsort.planning import (CupIK, JointTrajectory, MotionConfig, UnreachableWaypoint, Waypoint, plan_motion,
                                site_yaw)

# Cup heights [m] and offsets, from the cell's geometry (config.CellLayout).
CARRY_Z = 0.60  # cup height while carrying: the box bottom clears the belt rails by 8 cm
APPROACH_GAP = 0.04  # cup above the box's top face before the final descent
PRESS = 0.003  # the cup's target lies this far below the top face, so the pad seats firmly
DROP_CLEARANCE = 0.12  # box bottom above a bin's rim at release
WAIT_OFFSET_Y = 0.205  # wait pose this far from the belt centre, toward the bins (out of view)
DROP_SLOTS = 4  # release points per bin, used in turn so that boxes do not pile up


class Phase(Enum):
    MOVE_TO_WAIT = "move to wait pose"
    WAIT_FOR_BOX = "wait for box"
    LET_PASS = "let box pass"
    DESCEND = "descend"
    GRIP = "grip"
    BACK_UP = "back up"
    MOVE_OVER_BIN = "move over bin"
    RELEASE = "release"


@dataclass
class Cycle:
    """One box handled by the expert: what it saw and when [s, sim time]."""

    seen_color: str
    detected_at: float
    done_at: float | None = None
    target_bin: str | None = None  # None: let through


@dataclass
class _Motion:
    trajectory: JointTrajectory
    started: float
    tolerance: float  # [rad] max joint error that counts as arrived


@dataclass(frozen=True)
class ExpertConfig:
    """Settings of the scripted expert.

    Attributes:
        motion: joint speed, acceleration and jerk limits.
        perception: the colour sensor's thresholds.
        grip_timeout: [s] time to wait for a seal before backing off and looking again.
        release_time: [s] time after the seal is gone before moving on (the box falls clear).
        sensor_image_size: [px] side of the triggered photo, when the env's observations do not
            include ``sensor_image``.
    """

    motion: MotionConfig = field(default_factory=MotionConfig)
    perception: PerceptionConfig = field(default_factory=PerceptionConfig)
    grip_timeout: float = 1.0
    release_time: float = 0.15
    sensor_image_size: int = 128


class SortingExpert:
    """Sorts boxes from the belt into the bins of the colours its camera sees.

    Args:
        env: a ColorSort env with an off-screen renderer: the expert uses the ``sensor`` camera's
            observation if the env has one, else it takes a photo when the ray fires. It reads the
            env's calibration (camera pose, robot kinematics, controller gains), not its state.
        config: the expert's settings.

    Use: ``action = expert.act(obs)`` every step after ``expert.reset(obs)``.
    """

    def __init__(self, env: ColorSort, config: ExpertConfig = ExpertConfig()):
        if not env.has_offscreen_renderer:
            raise ValueError("The expert needs the sensor camera: make the env with has_offscreen_renderer=True")
        self.env = env
        self.config = config
        self.layout = env.layout
        self.dt = env.control_timestep
        robot = env.robots[0]
        self.n = len(robot.init_qpos)
        self.home = np.asarray(robot.init_qpos, float)
        self.max_velocity = np.array(ROBOT_JOINT_SPEEDS[robot.name])
        controller = robot.part_controllers["right"]
        # The position controller lags its target by kd/kp times the speed; leading the target
        # by as much makes the arm follow the planned trajectory (velocity feed-forward).
        self.lead = np.asarray(controller.kd, float) / np.asarray(controller.kp, float)
        self.ik = CupIK(robot.robot_model.get_model(mode="mujoco"), self.home)
        self.cup_yaw = site_yaw(self.ik.cup_pose(self.home)[1])  # a multiple of 90 deg: bins' axes
        self.photo_size: tuple[int, int] | None = None  # (width, height) [px] when taking photos itself
        if env.use_camera_obs and "sensor" in env.camera_names:
            i = env.camera_names.index("sensor")
            width, height = env.camera_widths[i], env.camera_heights[i]
        else:
            width = height = config.sensor_image_size
            self.photo_size = (width, height)
        camera = CameraModel.from_sim(env.sim.model._model, env.sim.data._data, "sensor", width, height)
        self.sensor = ColorSensor(camera, self.layout, config.perception)
        L = self.layout
        px, py, _ = L.pick_point
        self.q_wait = self.ik.solve(Waypoint("wait", (px, py + WAIT_OFFSET_Y, CARRY_Z), self.cup_yaw), self.home)
        self.q_drop = {color: self._drop_slots(color, k) for k, color in enumerate(BIN_COLORS)}
        self.reset()

    def _drop_slots(self, color: str, index: int) -> list[np.ndarray]:
        """Joint angles of up to ``DROP_SLOTS`` release points over a bin, nearest the robot first.

        Candidates lie on a grid inside the bin, far enough from its walls for a box of any yaw;
        those the arm cannot reach are skipped (the Panda reaches less far than the IRB 140).
        """
        L = self.layout
        bx, by = L.bin_center(index)
        margin = L.box_size / 2 + 0.01 + L.bin_wall  # an axis-aligned box 1 cm clear of the walls
        hx, hy = L.bin_size[0] / 2 - margin, L.bin_size[1] / 2 - margin
        z = L.bin_size[2] + DROP_CLEARANCE + L.box_size
        grid = [(bx + dx, by + dy) for dx in np.linspace(-hx, hx, 4) for dy in np.linspace(-hy, hy, 3)]
        grid.sort(key=lambda p: np.hypot(*p))
        slots = []
        for x, y in grid:
            try:
                slots.append(self.ik.solve(Waypoint(f"{color} bin drop", (x, y, z), self.cup_yaw), self.q_wait))
            except UnreachableWaypoint:
                continue
            if len(slots) == DROP_SLOTS:
                return slots
        if not slots:
            raise UnreachableWaypoint(f"No drop point over the {color} bin is within the arm's reach")
        return slots

    # ------------------------------------------------------------------ state
    def reset(self, obs: dict | None = None) -> None:
        """Start a new episode (from the arm's current joints if ``obs`` is given)."""
        self.phase = Phase.MOVE_TO_WAIT
        self.time = 0.0
        self.phase_started = 0.0
        self.motion: _Motion | None = None
        self.target: Detection | None = None
        self.suction = False
        self.belt_pass = False
        self.drops = {c: 0 for c in BIN_COLORS}
        self.cycles: list[Cycle] = []
        self._q_pick: dict[str, np.ndarray] = {}
        self._q_cmd = np.array(obs["robot0_joint_pos"], float) if obs is not None else self.home.copy()
        self._start_motion(self._q_cmd, self.q_wait, tolerance=0.02)

    @property
    def seen_color(self) -> str | None:
        """Colour of the box being handled, as the camera saw it, or None."""
        return self.cycles[-1].seen_color if self.cycles and self.cycles[-1].done_at is None else None

    def _enter(self, phase: Phase) -> None:
        self.phase, self.phase_started = phase, self.time

    def _start_motion(self, start: np.ndarray, goal: np.ndarray, tolerance: float) -> None:
        self.motion = _Motion(plan_motion(start, goal, self.max_velocity, self.config.motion), self.time, tolerance)

    def _arrived(self, q: np.ndarray) -> bool:
        m = self.motion
        return m is None or (self.time - m.started >= m.trajectory.duration
                             and float(np.max(np.abs(q - m.trajectory.goal))) < m.tolerance)

    # ------------------------------------------------------------------ policy
    def act(self, obs: dict) -> np.ndarray:
        """The action for this step: joint targets [rad], suction, belt pass."""
        q = np.asarray(obs["robot0_joint_pos"], float)
        self._transition(obs, q)
        if self.motion is not None:
            ref, vel, _ = self.motion.trajectory.sample(self.time - self.motion.started + self.dt)
            self._q_cmd = ref + self.lead * vel
        self.time += self.dt
        return np.concatenate([self._q_cmd, [1.0 if self.suction else -1.0, 1.0 if self.belt_pass else -1.0]])

    def _sensor_image(self, obs: dict) -> np.ndarray:
        if self.photo_size is None:
            return np.asarray(obs["sensor_image"])
        return self.env.camera_image("sensor", *self.photo_size)

    def _transition(self, obs: dict, q: np.ndarray) -> None:
        P = Phase
        L = self.layout
        detected = float(obs["box_detected"]) > 0.5
        sealed = float(obs["suction_sealed"]) > 0.5
        goal = self.motion.trajectory.goal if self.motion is not None else self._q_cmd
        if self.phase is P.MOVE_TO_WAIT:
            if self._arrived(q):
                if self.cycles and self.cycles[-1].done_at is None:
                    self.cycles[-1].done_at = self.time  # a cycle ends with the arm ready again
                self._enter(P.WAIT_FOR_BOX)
        if self.phase is P.WAIT_FOR_BOX and detected:
            self.target = self.sensor.box_at_sensor(self._sensor_image(obs))
            t = self.target
            pickable = t is not None and t.complete and t.color in BIN_COLORS
            self.cycles.append(Cycle(t.color if t is not None else "none", self.time,
                                     target_bin=t.color if pickable else None))
            if not pickable:
                self.belt_pass = True
                self._enter(P.LET_PASS)
            else:
                yaw = self.cup_yaw + t.yaw  # the cube's yaw nearest the cup's: t.yaw is in [-45, 45) deg
                top = L.belt_top_z + L.box_size
                above = Waypoint("above box", (t.center[0], t.center[1], top + APPROACH_GAP), yaw)
                self._q_pick["above"] = self.ik.solve(above, self.q_wait)
                self._q_pick["contact"] = self.ik.solve(
                    Waypoint("on box", (t.center[0], t.center[1], top - PRESS), yaw), self._q_pick["above"])
                self._q_pick["lift"] = self.ik.solve(
                    Waypoint("lift", (t.center[0], t.center[1], CARRY_Z), yaw), self._q_pick["contact"])
                self._start_motion(goal, self._q_pick["above"], tolerance=0.01)
                self._enter(P.DESCEND)
        elif self.phase is P.LET_PASS:
            if not detected:
                self.belt_pass = False
                self.cycles[-1].done_at = self.time
                self._enter(P.WAIT_FOR_BOX)
        elif self.phase is P.DESCEND:
            if self._arrived(q):
                if not self.suction:  # over the box: suction on for the last few centimetres
                    self.suction = True
                    self._start_motion(goal, self._q_pick["contact"], tolerance=0.01)
                else:
                    self._enter(P.GRIP)
        elif self.phase is P.GRIP:
            if sealed:
                self._start_motion(goal, self._q_pick["lift"], tolerance=0.05)
                self._enter(P.BACK_UP)
            elif self.time - self.phase_started > self.config.grip_timeout:
                self.suction = False  # no seal: back off and look again
                self.cycles.pop()
                self._start_motion(goal, self.q_wait, tolerance=0.02)
                self._enter(P.MOVE_TO_WAIT)
        elif self.phase is P.BACK_UP:
            if self._arrived(q):
                color = self.cycles[-1].target_bin
                slots = self.q_drop[color]
                self._start_motion(goal, slots[self.drops[color] % len(slots)], tolerance=0.03)
                self.drops[color] += 1
                self._enter(P.MOVE_OVER_BIN)
        elif self.phase is P.MOVE_OVER_BIN:
            if self._arrived(q):
                self.suction = False
                self._enter(P.RELEASE)
        elif self.phase is P.RELEASE:
            if not sealed and self.time - self.phase_started >= self.config.release_time:
                self._start_motion(goal, self.q_wait, tolerance=0.02)
                self._enter(P.MOVE_TO_WAIT)
