"""The scripted sorting expert: the original cell's phases, one handler each.

It acts only on what a real cell has: the ray sensor (``box_detected``), the colour camera (the
``sensor_image`` observation, or a photo it triggers when the ray fires), the arm's joint angles
(``robot0_joint_pos``) and the cup's vacuum switch (``suction_sealed``), with a ``Calibration`` of
the cell. Waypoints come from mink IK, motions from ruckig (``planning.py``); what it shares with
the tracking expert (the motion follower, the look, the drop slots, the release) is ``base.py``.

Phases (the original's numbering):

1. ``MOVE_TO_WAIT``: move to the wait pose, beside and above the pick point, out of the camera's view;
2. ``WAIT_FOR_BOX``: hold until the ray sees a box, then look: a box of a bin colour is picked,
   any other (or none seen) is let through (``LET_THROUGH``: belt-pass on until the ray clears);
3. ``APPROACH``: fast to over the box where the camera saw it, clear of the tallest box the cell
   accepts, cup turned to its yaw, ending on the way down;
4. ``DESCEND``: suction on, the touch-off (``touch.py``): guarded, straight down until the vacuum switch
   reports a seal; at the floor with none, ``BACK_OFF`` (straight up, the pick given up and its reason kept
   in ``misses``) and look again;
5. ``BACK_UP``: straight up, from wherever the seal formed;
6. ``MOVE_OVER_BIN``: to the next drop slot over the bin of the colour seen;
7. ``RELEASE``: suction off until the seal is gone and the box has fallen clear;
8. emptying full bins is the cell's own job here: ``ColorSort`` empties a bin when it is full.

``CLEAR`` starts a take-over from any state of the cell (``Expert.take_over``): straight up, then on to the bin of
a held box's colour (``MOVE_OVER_BIN``) or to the wait pose.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np

from colorsort.expert.base import Expert, Handler, ray_blocked, sealed
from colorsort.expert.perception import Detection
from colorsort.expert.planning import DensePath, Waypoint, plan_motion
from colorsort.expert.touch import straight_path


class SorterPhase(Enum):
    """The stopping-belt expert's phases."""

    MOVE_TO_WAIT = "move to wait pose"
    WAIT_FOR_BOX = "wait for box"
    LET_THROUGH = "let box through"
    APPROACH = "approach box"
    DESCEND = "descend"
    BACK_OFF = "back off"
    BACK_UP = "back up"
    MOVE_OVER_BIN = "move over bin"
    RELEASE = "release"
    CLEAR = "lift clear"  # a take-over's first motion (``Expert.take_over``)


@dataclass(frozen=True)
class PickPlan:
    """One pick: the cup over the box (joint angles [rad]), the touch-off's way down, and where it lifts to."""

    above: np.ndarray
    descent: DensePath
    x: float  # [m] the box's centre as seen
    y: float
    yaw: float  # [rad] the cup's


class SortingExpert(Expert):
    """Sorts boxes from a belt that stops at the ray into the bins of the colours its camera sees.

    Args: as ``base.Expert``. Use: ``expert = make_expert(env)`` (``expert/factory.py``), then
    ``action = expert.act(obs)`` every step after ``expert.reset(obs)``.
    """

    START = SorterPhase.MOVE_TO_WAIT
    APPROACH = SorterPhase.APPROACH
    CLEAR = SorterPhase.CLEAR
    OVER_BIN = SorterPhase.MOVE_OVER_BIN

    def handlers(self) -> dict[Enum, Handler]:
        return {
            SorterPhase.MOVE_TO_WAIT: self._move_to_wait, SorterPhase.WAIT_FOR_BOX: self._wait_for_box,
            SorterPhase.LET_THROUGH: self._let_through, SorterPhase.APPROACH: self._approach,
            SorterPhase.DESCEND: self._descend, SorterPhase.BACK_OFF: self._back_off,
            SorterPhase.BACK_UP: self._back_up,
            SorterPhase.MOVE_OVER_BIN: self._move_over_bin, SorterPhase.RELEASE: self._release,
            SorterPhase.CLEAR: self._clear,
        }

    def drop_seed(self) -> np.ndarray:
        """The wait pose, beside the bins."""
        return self.q_wait

    def wait_point(self) -> tuple[float, float, float]:
        """Beside and above the pick point, toward the bins, out of the camera's view [m]."""
        px, py, _ = self.layout.pick_point
        return (px, py + self.config.wait_offset_y, self.config.carry_z)

    def reset(self, obs: dict | None = None) -> None:
        self.target: Detection | None = None
        self.pick: PickPlan | None = None
        super().reset(obs)

    # 1. move to the wait pose
    def _move_to_wait(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        if self._arrived(q):
            if self.cycles and self.cycles[-1].done_at is None:
                self.cycles[-1].done_at = self.time  # a cycle ends with the arm ready again
            self._enter(SorterPhase.WAIT_FOR_BOX)
            self._wait_for_box(obs, q, goal)  # a box already at the ray is seen in the same step

    # 2. wait for a box, look at it
    def _wait_for_box(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        if not ray_blocked(obs):
            return
        self.target, cycle = self._look(obs)
        if self.target is None or cycle.target_bin is None:
            self.belt_pass = True
            self._enter(SorterPhase.LET_THROUGH)
            return
        self.pick = self._plan_pick(self.target)
        descending = self.pick.descent.qd[0]  # the approach ends on its way down
        self._follow(plan_motion(goal, self.pick.above, self.limits, goal_velocity=descending),
                     self.config.approach_tolerance)
        self._enter(SorterPhase.APPROACH)

    def _plan_pick(self, t: Detection) -> PickPlan:
        cfg = self.config
        yaw = self.cup_yaw + self.turn(t)
        x, y = float(t.center[0]), float(t.center[1])
        above = self.ik.solve(Waypoint("above box", (x, y, self.descent.start), yaw), self.q_wait)
        down = straight_path(self.ik, (x, y, self.descent.start), (0.0, 0.0, -cfg.touch_speed), yaw,
                             self.descent.duration(cfg.touch_speed), self.dt, above)
        return PickPlan(above, down, x, y, yaw)

    # 2'. a box with no bin (or none seen): run the belt until the ray clears
    def _let_through(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        if not ray_blocked(obs):
            self.belt_pass = False
            self.cycles[-1].done_at = self.time
            self._enter(SorterPhase.WAIT_FOR_BOX)

    # 3. over the box, on the way down as the approach ends; 4. the touch-off
    def _approach(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        assert self.motion is not None and self.pick is not None, "APPROACH follows a planned pick"
        if self.motion.done(self.time + self.dt):  # it ends before the next command: the descent follows on at once
            self.suction = True
            self._follow(self.pick.descent, np.inf, started=self.motion.end)
            self._enter(SorterPhase.DESCEND)

    def _descend(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        assert self.motion is not None and self.pick is not None, "DESCEND follows a planned pick"
        p = self.pick
        if sealed(obs):  # the part is present: stop where it is (not at the planner's jerk) and lift it from there
            here = self._current_state()[0]
            lift = self.ik.solve(Waypoint("lift", (p.x, p.y, self.config.carry_z), p.yaw), here)
            self._start_motion(here, lift, self.config.lift_tolerance)
            self._enter(SorterPhase.BACK_UP)
        elif self.motion.done(self.time):  # down to the floor with no seal: nothing there to pick
            self.suction = False
            self.misses.append((self.time, f"no seal down to the floor ({self.descent.floor:.3f} m) at "
                                           f"({p.x:.3f}, {p.y:.3f}) m"))
            self._start_from_here(p.above, self.config.lift_tolerance)
            self._enter(SorterPhase.BACK_OFF)

    def _back_off(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        """Up clear of any box, then to the wait pose to look again (the pick's cycle given up)."""
        if self._arrived(q):
            self.cycles.pop()
            self._start_motion(goal, self.q_wait, self.config.wait_tolerance)
            self._enter(SorterPhase.MOVE_TO_WAIT)

    # 5. back up, then 6. move over the bin of the colour seen
    def _back_up(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        if self._arrived(q):
            color = self.cycles[-1].target_bin
            assert color is not None, "only a box with a bin is picked"
            self._start_motion(goal, self._next_drop(color), self.config.drop_tolerance)
            self._enter(SorterPhase.MOVE_OVER_BIN)

    def _move_over_bin(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        if self._arrived(q):
            self.suction = False
            self._enter(SorterPhase.RELEASE)

    # 7. release: wait until the seal is gone and the box has fallen clear
    def _release(self, obs: dict, q: np.ndarray, goal: np.ndarray) -> None:
        if self._released(obs):
            self._start_motion(goal, self.q_wait, self.config.wait_tolerance)
            self._enter(SorterPhase.MOVE_TO_WAIT)
