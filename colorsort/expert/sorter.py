"""The scripted sorting expert: the original cell's phases, one handler each.

It acts only on what a real cell has: the ray sensor (``box_detected``), the colour camera (the
``sensor_image`` observation, or a photo it triggers when the ray fires), the arm's joint angles
(``robot0_joint_pos``) and the cup's vacuum switch (``suction_sealed``), with a ``Calibration`` of
the cell. Waypoints come from mink IK, motions from ruckig (``planning.py``).

Phases (the original's numbering):

1. ``MOVE_TO_WAIT``: move to the wait pose, beside and above the pick point, out of the camera's view;
2. ``WAIT_FOR_BOX``: hold until the ray sees a box, then look: a box of a bin colour is picked,
   any other (or none seen) is let through (``LET_THROUGH``: belt-pass on until the ray clears);
3. ``APPROACH``: over the box where the camera saw it, cup turned to its yaw;
   ``DESCEND``: suction on, down onto the box;
4. ``GRIP``: hold until the vacuum switch reports a seal;
5. ``BACK_UP``: straight up;
6. ``MOVE_OVER_BIN``: to the next drop slot over the bin of the colour seen;
7. ``RELEASE``: suction off until the seal is gone and the box has fallen clear;
8. emptying full bins is the cell's own job here: ``ColorSort`` empties a bin when it is full.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING

import numpy as np

from colorsort.config import BIN_COLORS
from colorsort.expert.calibration import Calibration
from colorsort.expert.config import ExpertConfig
from colorsort.expert.perception import ColorSensor, Detection, bin_for
from colorsort.expert.planning import CupIK, Trajectory, UnreachableWaypoint, Waypoint, plan_motion, site_yaw

if TYPE_CHECKING:
    pass


class Phase(Enum):
    MOVE_TO_WAIT = "move to wait pose"
    WAIT_FOR_BOX = "wait for box"
    LET_THROUGH = "let box through"
    APPROACH = "approach box"
    DESCEND = "descend"
    INTERCEPT = "intercept box"  # tracking: over the moving box, moving with it
    TRACK = "track box"  # tracking: down onto the moving box, seal and lift, moving with it
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


@dataclass(frozen=True)
class PickPlan:
    """Joint angles [rad] of one pick: over the box, on it, and lifted."""

    above: np.ndarray
    contact: np.ndarray
    lift: np.ndarray


@dataclass
class _Motion:
    trajectory: Trajectory
    started: float
    tolerance: float  # [rad] max joint error that counts as arrived


class SortingExpert:
    """Sorts boxes from the belt into the bins of the colours its camera sees.

    Args:
        calibration: the cell as the expert knows it (``Calibration.from_env``).
        sensor_image: the colour image for an observation (``calibration.sensor_source``).
        config: the expert's settings.

    Use: ``expert = make_expert(env)`` (``expert/factory.py``), then ``action = expert.act(obs)`` every step after
    ``expert.reset(obs)``.
    """

    def __init__(self, calibration: Calibration, sensor_image: Callable[[dict], np.ndarray],
                 config: ExpertConfig = ExpertConfig()):
        self.calibration, self.config = calibration, config
        self.sensor_image = sensor_image
        self.layout = L = calibration.layout
        self.dt = calibration.control_period
        self.home = calibration.home
        self.ik = CupIK(calibration.kinematics, self.home)
        self.cup_yaw = site_yaw(self.ik.cup_pose(self.home)[1])  # a multiple of 90 deg: bins' axes
        self.sensor = ColorSensor(calibration.camera, L, config.perception)
        self.q_wait = self.ik.solve(Waypoint("wait", self._wait_point(), self.cup_yaw), self.home)
        self.q_drop = {color: self._drop_slots(color, k) for k, color in enumerate(BIN_COLORS)}
        self._handlers: dict[Phase, Callable[[dict, np.ndarray, np.ndarray], None]] = {
            Phase.MOVE_TO_WAIT: self._move_to_wait, Phase.WAIT_FOR_BOX: self._wait_for_box,
            Phase.LET_THROUGH: self._let_through, Phase.APPROACH: self._approach, Phase.DESCEND: self._descend,
            Phase.GRIP: self._grip, Phase.BACK_UP: self._back_up, Phase.MOVE_OVER_BIN: self._move_over_bin,
            Phase.RELEASE: self._release,
        }
        self.reset()

    def _drop_seed(self) -> np.ndarray:
        """The joint angles [rad] the drop points' IK starts from: the wait pose, beside the bins."""
        return self.q_wait

    def _wait_point(self) -> tuple[float, float, float]:
        """Where the cup waits for a box [m]: beside and above the pick point, toward the bins, out of view."""
        px, py, _ = self.layout.pick_point
        return (px, py + self.config.wait_offset_y, self.config.carry_z)

    def _drop_slots(self, color: str, index: int) -> list[np.ndarray]:
        """Joint angles of up to ``drop_slots`` release points over a bin, nearest the robot first.

        Candidates lie on a grid inside the bin, far enough from its walls for a box of any yaw;
        those the arm cannot reach are skipped (the Panda reaches less far than the IRB 140).
        """
        L, cfg = self.layout, self.config
        bx, by = L.bin_center(index)
        margin = L.box_size / 2 + 0.01 + L.bin_wall  # an axis-aligned box 1 cm clear of the walls
        hx, hy = L.bin_size[0] / 2 - margin, L.bin_size[1] / 2 - margin
        z = L.bin_size[2] + cfg.drop_clearance + L.box_size
        grid = [(bx + dx, by + dy) for dx in np.linspace(-hx, hx, 4) for dy in np.linspace(-hy, hy, 3)]
        grid.sort(key=lambda p: np.hypot(*p))
        slots = []
        for x, y in grid:
            try:
                slots.append(self.ik.solve(Waypoint(f"{color} bin drop", (x, y, z), self.cup_yaw), self._drop_seed()))
            except UnreachableWaypoint:
                continue
            if len(slots) == cfg.drop_slots:
                return slots
        if not slots:
            raise UnreachableWaypoint(f"No drop point over the {color} bin is within the arm's reach")
        return slots

    def reset(self, obs: dict | None = None) -> None:
        """Start a new episode (from the arm's current joints if ``obs`` is given)."""
        self.phase = Phase.MOVE_TO_WAIT
        self.time = 0.0
        self.phase_started = 0.0
        self.motion: _Motion | None = None
        self.target: Detection | None = None
        self.pick: PickPlan | None = None
        self.suction = False
        self.belt_pass = False
        self.drops = {c: 0 for c in BIN_COLORS}
        self.cycles: list[Cycle] = []
        self._q_cmd = np.array(obs["robot0_joint_pos"], float) if obs is not None else self.home.copy()
        self._start_motion(self._q_cmd, self.q_wait, self.config.wait_tolerance)

    @property
    def seen_color(self) -> str | None:
        """Colour of the box being handled, as the camera saw it, or None."""
        return self.cycles[-1].seen_color if self.cycles and self.cycles[-1].done_at is None else None

    def act(self, obs: dict) -> np.ndarray:
        """The action for this step: joint targets [rad], suction, belt pass."""
        q = np.asarray(obs["robot0_joint_pos"], float)
        goal = self.motion.trajectory.goal if self.motion is not None else self._q_cmd
        self._handlers[self.phase](obs, q, goal)
        if self.motion is not None:
            ref, vel, _ = self.motion.trajectory.sample(self.time - self.motion.started + self.dt)
            self._q_cmd = ref + self.calibration.lead * vel
        self.time += self.dt
        return np.concatenate([self._q_cmd, [1.0 if self.suction else -1.0, 1.0 if self.belt_pass else -1.0]])

    def _enter(self, phase: Phase) -> None:
        self.phase, self.phase_started = phase, self.time

    def _start_motion(self, start: np.ndarray, goal: np.ndarray, tolerance: float) -> None:
        trajectory = plan_motion(start, goal, self.calibration.max_velocity, self.config.motion)
        self.motion = _Motion(trajectory, self.time, tolerance)

    def _arrived(self, q: np.ndarray) -> bool:
        m = self.motion
        return m is None or (self.time - m.started >= m.trajectory.duration
                             and float(np.max(np.abs(q - m.trajectory.goal))) < m.tolerance)

    # 1. move to the wait pose
    def _move_to_wait(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        if self._arrived(q):
            if self.cycles and self.cycles[-1].done_at is None:
                self.cycles[-1].done_at = self.time  # a cycle ends with the arm ready again
            self._enter(Phase.WAIT_FOR_BOX)
            self._wait_for_box(obs, q, goal)  # a box already at the ray is seen in the same step

    # 2. wait for a box, look at it
    def _wait_for_box(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        if float(obs["box_detected"]) <= 0.5:
            return
        self.target = t = self.sensor.box_at_sensor(self.sensor_image(obs))
        target_bin = bin_for(t)
        self.cycles.append(Cycle(t.color if t is not None else "none", self.time, target_bin=target_bin))
        if t is None or target_bin is None:
            self.belt_pass = True
            self._enter(Phase.LET_THROUGH)
            return
        self.pick = self._plan_pick(t)
        self._start_motion(goal, self.pick.above, self.config.approach_tolerance)
        self._enter(Phase.APPROACH)

    def _plan_pick(self, t: Detection) -> PickPlan:
        L, cfg = self.layout, self.config
        yaw = self.cup_yaw + t.yaw  # the cube's yaw nearest the cup's: t.yaw is in [-45, 45) deg
        x, y = t.center[0], t.center[1]
        top = L.belt_top_z + L.box_size
        above = self.ik.solve(Waypoint("above box", (x, y, top + cfg.approach_gap), yaw), self.q_wait)
        contact = self.ik.solve(Waypoint("on box", (x, y, top - cfg.press), yaw), above)
        lift = self.ik.solve(Waypoint("lift", (x, y, cfg.carry_z), yaw), contact)
        return PickPlan(above, contact, lift)

    # 2'. a box with no bin (or none seen): run the belt until the ray clears
    def _let_through(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        if float(obs["box_detected"]) <= 0.5:
            self.belt_pass = False
            self.cycles[-1].done_at = self.time
            self._enter(Phase.WAIT_FOR_BOX)

    # 3. over the box, then suction on and down onto it
    def _approach(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        if self._arrived(q):
            self.suction = True  # on for the last few centimetres
            assert self.pick is not None, "APPROACH follows a planned pick"
            self._start_motion(goal, self.pick.contact, self.config.approach_tolerance)
            self._enter(Phase.DESCEND)

    def _descend(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        if self._arrived(q):
            self._enter(Phase.GRIP)

    # 4. grip: wait for the vacuum switch
    def _grip(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        if float(obs["suction_sealed"]) > 0.5:
            assert self.pick is not None, "GRIP follows a planned pick"
            self._start_motion(goal, self.pick.lift, self.config.lift_tolerance)
            self._enter(Phase.BACK_UP)
        elif self.time - self.phase_started > self.config.grip_timeout:
            self.suction = False  # no seal: back off and look again
            self.cycles.pop()
            self._start_motion(goal, self.q_wait, self.config.wait_tolerance)
            self._enter(Phase.MOVE_TO_WAIT)

    # 5. back up, then 6. move over the bin of the colour seen
    def _back_up(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        if self._arrived(q):
            color = self.cycles[-1].target_bin
            assert color is not None, "only a box with a bin is picked"
            slots = self.q_drop[color]
            self._start_motion(goal, slots[self.drops[color] % len(slots)], self.config.drop_tolerance)
            self.drops[color] += 1
            self._enter(Phase.MOVE_OVER_BIN)

    def _move_over_bin(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        if self._arrived(q):
            self.suction = False
            self._enter(Phase.RELEASE)

    # 7. release: wait until the seal is gone and the box has fallen clear
    def _release(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        sealed = float(obs["suction_sealed"]) > 0.5
        if not sealed and self.time - self.phase_started >= self.config.release_time:
            self._start_motion(goal, self.q_wait, self.config.wait_tolerance)
            self._enter(Phase.MOVE_TO_WAIT)
